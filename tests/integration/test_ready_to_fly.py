"""Ready to fly, end to end against the simulated ArduCopter: a 3D fix the EKF does not
use yet is shown as not ready, with the reason, and a take-off refused meanwhile names
it; once the EKF takes the GPS (10 s of sim time later) the vehicle is ready and flies.
"""

from __future__ import annotations

import asyncio
import time

import pytest
from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from protocol.messages import CommandOutcome, TakeoffCommand, VehicleState
from tests.support.fcu import fcu_url, on_link, simulated
from vehicle_agents.control.executor import CommandExecutor
from vehicle_agents.fcu.link import FcuLink
from vehicle_agents.telemetry.snapshot import link_snapshot

pytestmark = pytest.mark.integration

EKF_REASON = "EKF has no position estimate yet (not using the GPS)"


async def state_where(link: FcuLink, wanted: bool, within_s: float) -> VehicleState:
    """The agent's snapshot once ``ready_to_fly`` is ``wanted`` (waits on the messages
    that decide it)."""
    deadline = time.monotonic() + within_s
    while (state := link_snapshot(link)).ready_to_fly is not wanted:
        if time.monotonic() > deadline:
            raise AssertionError(f"ready_to_fly never became {wanted}: {state}")
        await link.wait_for(lambda m: m.get_type() in ("EKF_STATUS_REPORT", "SYS_STATUS"), 2.0)
    return state


def test_a_fix_the_ekf_does_not_use_yet_is_not_ready_and_take_off_says_why() -> None:
    with simulated("ardupilot") as server:

        async def body(
            executor: CommandExecutor,
        ) -> tuple[VehicleState, CommandOutcome, VehicleState, CommandOutcome]:
            link = executor.link
            # as the agent's stream requests do (streams.DEFAULT_RATES_HZ), at 5 Hz
            interval = await executor.command_long(
                mavlink2.MAV_CMD_SET_MESSAGE_INTERVAL,
                [mavlink2.MAVLINK_MSG_ID_EKF_STATUS_REPORT, 200_000],
            )
            assert interval.status == "accepted", interval
            await link.wait_for(lambda m: m.get_type() == "EKF_STATUS_REPORT", 5)
            await state_where(link, True, 10)
            # GPS lost, then back: a 3D fix at once, the EKF's 10 s wait after it
            server.copter.set_gps_fix(1)
            server.copter.set_gps_fix(3)
            waiting = await state_where(link, False, 10)
            refused = await executor.execute(TakeoffCommand(altitude=5))
            ready = await state_where(link, True, 30)
            flown = await executor.execute(TakeoffCommand(altitude=5))
            return waiting, refused, ready, flown

        waiting, refused, ready, flown = asyncio.run(on_link(fcu_url(server), body))
    assert waiting.gps_fix == 3, "the operator sees a good fix ..."
    assert waiting.not_ready_reason == EKF_REASON, "... and why the vehicle is not ready"
    assert refused.status == "refused"
    assert "Arm: Need Position Estimate" in refused.message
    assert refused.message.endswith(f"; not ready to fly: {EKF_REASON}")
    assert (ready.ready_to_fly, ready.not_ready_reason) == (True, None)
    assert flown.status == "accepted", flown
