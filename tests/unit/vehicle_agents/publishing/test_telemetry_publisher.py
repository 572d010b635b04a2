"""An arming shorter than the telemetry period still reaches the hub, whose flight log
finds flights from arm to disarm: the agent takes a snapshot as each HEARTBEAT that
changes the armed state is handled, even with the disarm right behind it in one read
from the wire (a take-off landed straight away, as step 4 of docs/integrator.md's client
steps does)."""

from __future__ import annotations

import asyncio
from typing import Any

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from protocol.messages import Telemetry, agent_to_hub
from vehicle_agents.fcu.link import FcuLink
from vehicle_agents.hub.outbox import Outbox
from vehicle_agents.publishing.telemetry import TelemetryPublisher

VEHICLE = 1
GUIDED = 4


def _heartbeat(armed: bool) -> Any:
    flags = mavlink2.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED
    if armed:
        flags |= mavlink2.MAV_MODE_FLAG_SAFETY_ARMED
    return mavlink2.MAVLink_heartbeat_message(
        mavlink2.MAV_TYPE_QUADROTOR,
        mavlink2.MAV_AUTOPILOT_ARDUPILOTMEGA,
        flags,
        GUIDED,
        mavlink2.MAV_STATE_ACTIVE,
        3,
    )


async def _published(armed_in_one_read: list[bool], component: int = 1) -> list[Telemetry]:
    """The snapshots in the outbox after a periodic one and then these heartbeats from
    the vehicle's ``component``, handed over in one batch as the link's reader thread
    does (the autopilot is component 1)."""
    link = FcuLink("tcp:127.0.0.1:1")
    link.target_system = VEHICLE
    outbox = Outbox("s", limit=100)
    publisher = TelemetryPublisher(link, outbox)
    publisher.publish()  # the rate's snapshot, before the heartbeats
    mav = mavlink2.MAVLink(None, srcSystem=VEHICLE, srcComponent=component)
    link._inbox.extend(
        mav.decode(bytearray(_heartbeat(armed).pack(mav))) for armed in armed_in_one_read
    )
    link._deliver_inbox()
    outbox.link_up()
    frames = [await asyncio.wait_for(outbox.next_frame(), 5) for _ in range(len(outbox))]
    snapshots = [agent_to_hub.decode(frame) for frame in frames]
    assert all(isinstance(snapshot, Telemetry) for snapshot in snapshots), snapshots
    return snapshots  # type: ignore[return-value]


def test_an_arm_and_a_disarm_between_two_snapshots_are_both_published() -> None:
    snapshots = asyncio.run(_published([True, False]))
    assert [s.state.armed for s in snapshots] == [False, True, False]
    assert [s.seq for s in snapshots] == [0, 1, 2]  # one numbering with the rate's


def test_heartbeats_that_change_nothing_add_no_snapshot() -> None:
    snapshots = asyncio.run(_published([False, False, True, True]))
    assert [s.state.armed for s in snapshots] == [False, True]


def test_another_component_s_heartbeat_adds_no_snapshot() -> None:
    """A camera or gimbal on the same system sends heartbeats of its own, which say
    nothing of the motors."""
    snapshots = asyncio.run(_published([True], component=mavlink2.MAV_COMP_ID_CAMERA))
    assert len(snapshots) == 1
