"""MAV_RESULT names and the frames position commands go in, per autopilot.

The result codes come from a scripted flight controller (tests/support/mavlink_peer.py) over
real TCP; the frames are checked against the simulator's PX4 and ArduCopter
personalities, which refuse what the real autopilots refuse.
"""

from __future__ import annotations

import asyncio

import pytest
from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from protocol.messages import ChangeSpeedCommand, CommandOutcome, GotoCommand, SetHomeCommand
from simulator.config import DEFAULT_HOME, Autopilot
from simulator.copter import Copter
from tests.support.fcu import fcu_url, on_link, simulated
from tests.support.mavlink_peer import Answer, ScriptedFlightController
from vehicle_agents.control.executor import CommandExecutor
from vehicle_agents.fcu.messages import MavMessage
from vehicle_agents.fcu.results import result_name

pytestmark = pytest.mark.integration


# -- MAV_RESULT names -------------------------------------------------------------------


def test_every_standard_result_code_has_its_name_and_others_show_their_number() -> None:
    """The current standard's codes by name (pymavlink's dialect ends at 8 and calls 9
    its ENUM_END); a code newer than the table reads as its number."""
    expected = [
        "ACCEPTED",
        "TEMPORARILY_REJECTED",
        "DENIED",
        "UNSUPPORTED",
        "FAILED",
        "IN_PROGRESS",
        "CANCELLED",
        "COMMAND_LONG_ONLY",
        "COMMAND_INT_ONLY",
        "COMMAND_UNSUPPORTED_MAV_FRAME",
        "NOT_IN_CONTROL",
    ]
    assert [result_name(code) for code in range(11)] == [f"MAV_RESULT_{n}" for n in expected]
    assert result_name(11) == "MAV_RESULT 11"
    assert result_name(200) == "MAV_RESULT 200"


def test_a_refusal_names_the_result_the_flight_controller_sent() -> None:
    """Result codes 6, 9 and an unknown 42, as COMMAND_ACKs on the wire, reach the
    operator by name (or by number), never as MAV_RESULT_ENUM_END."""
    speed = mavlink2.MAV_CMD_DO_CHANGE_SPEED

    def answer(message: MavMessage) -> list[Answer]:
        return [Answer(0.0, int(message.param2))]  # the speed asked for is the answer

    async def body(executor: CommandExecutor) -> list[CommandOutcome]:
        return [await executor.execute(ChangeSpeedCommand(speed=code)) for code in (6, 9, 42)]

    with ScriptedFlightController() as fcu:
        fcu.scripts[speed] = answer
        outcomes = asyncio.run(on_link(f"tcp:127.0.0.1:{fcu.port}", body))
    assert [o.status for o in outcomes] == ["refused"] * 3
    assert [o.result for o in outcomes] == [
        "MAV_RESULT_CANCELLED",
        "MAV_RESULT_COMMAND_UNSUPPORTED_MAV_FRAME",
        "MAV_RESULT 42",
    ]
    assert outcomes[1].message.startswith(
        "MAV_CMD_DO_CHANGE_SPEED: MAV_RESULT_COMMAND_UNSUPPORTED_MAV_FRAME"
    )


# -- frames of position commands, against the simulator's personalities ---------------


GOTO = GotoCommand(lat=DEFAULT_HOME.lat + 0.0003, lon=DEFAULT_HOME.lon + 0.0002, altitude=15)
NEW_HOME = SetHomeCommand(
    use_current=False,
    lat=DEFAULT_HOME.lat + 0.0001,
    lon=DEFAULT_HOME.lon - 0.0001,
    alt_msl=DEFAULT_HOME.alt + 2,
)


@pytest.mark.parametrize("autopilot", ["px4", "ardupilot"])
def test_goto_and_set_home_go_in_the_frame_each_autopilot_takes(autopilot: Autopilot) -> None:
    """PX4 takes DO_REPOSITION and DO_SET_HOME only in MAV_FRAME_GLOBAL_INT: the agent
    turns the altitude above home into one above sea level for it, and the vehicle
    ends up where it was asked to, on either autopilot."""

    async def body(executor: CommandExecutor) -> list[CommandOutcome]:
        return [await executor.execute(GOTO), await executor.execute(NEW_HOME)]

    with simulated(autopilot) as server:
        goto, set_home = asyncio.run(on_link(fcu_url(server), body))
        assert goto.status == "accepted", goto
        assert set_home.status == "accepted", set_home
        copter = server.copter
        assert isinstance(copter, Copter)
        target = copter.guided_target  # (north, east, metres above the origin)
        home = copter.home
    assert target is not None
    assert target[2] == pytest.approx(15.0, abs=0.01), "15 m above home, whatever the frame"
    assert (home.lat, home.lon) == pytest.approx((NEW_HOME.lat, NEW_HOME.lon), abs=1e-7)
    assert home.alt == pytest.approx(DEFAULT_HOME.alt + 2, abs=0.01)


def test_the_px4_simulator_refuses_other_frames_as_px4_does() -> None:
    """A reposition above home (MAV_FRAME_GLOBAL_RELATIVE_ALT_INT) gets MAV_RESULT 9."""

    async def body(executor: CommandExecutor) -> CommandOutcome:
        return await executor.command_int(
            mavlink2.MAV_CMD_DO_REPOSITION,
            mavlink2.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT,
            [-1, mavlink2.MAV_DO_REPOSITION_FLAGS_CHANGE_MODE, 0, float("nan")],
            GOTO.lat,
            GOTO.lon,
            GOTO.altitude,
        )

    with simulated("px4") as server:
        outcome = asyncio.run(on_link(fcu_url(server), body))
    assert outcome.status == "refused"
    assert outcome.result == "MAV_RESULT_COMMAND_UNSUPPORTED_MAV_FRAME"
