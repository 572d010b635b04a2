"""The deadman counts the autopilot's seconds (a sped-up simulator flies further on a
stale stick in a wall second), never fewer than the wall's; the first frame's grace is
the wall's, as the hub's lease expiry it outlasts."""

from __future__ import annotations

import asyncio

from protocol.messages import EventKind
from tests.support.paced import FakeWall, paced_at
from vehicle_agents.control.executor import CommandExecutor
from vehicle_agents.control.manual import ManualPilot
from vehicle_agents.fcu.link import FcuLink


def _pilot(rate: float) -> tuple[ManualPilot, FakeWall, list[str]]:
    """Browser control open, a frame flown just now, on an autopilot at ``rate``."""
    wall = FakeWall()
    link = FcuLink("tcp:127.0.0.1:1")  # down: the hold's command is tried and refused
    events: list[str] = []

    def emit(kind: EventKind, text: str, severity: int | None) -> None:
        events.append(text)

    clock = paced_at(rate, wall)
    pilot = ManualPilot(link, CommandExecutor(link), emit, clock=clock, wall=wall)
    pilot.active = True
    pilot._last_seq = 0  # a frame was flown
    pilot._last_at = clock()
    return pilot, wall, events


def _silence(pilot: ManualPilot, wall: FakeWall, seconds: float) -> bool:
    """Whether ``seconds`` of the wall's without a frame held the vehicle."""
    wall.now += seconds
    asyncio.run(pilot.check())
    return not pilot.active


def test_a_sped_up_autopilot_is_held_after_half_a_second_of_its_own() -> None:
    pilot, wall, events = _pilot(4.0)
    assert not _silence(pilot, wall, 0.1)  # 0.4 s of the simulator's
    assert _silence(pilot, wall, 0.05)  # 0.6 s
    assert events[0].startswith("manual input stopped for 0.60 s: holding"), events


def test_a_stalled_autopilot_clock_still_trips_the_deadman_in_wall_time() -> None:
    pilot, wall, events = _pilot(0.0)  # its clock stopped counting (or its link is gone)
    assert not _silence(pilot, wall, 0.4)
    assert _silence(pilot, wall, 0.2)
    assert "manual input stopped for 0.60 s" in events[0]


def test_the_first_frames_grace_is_the_wall_clocks() -> None:
    pilot, wall, _ = _pilot(4.0)
    pilot._last_seq = -1  # no frame yet since the lease's start
    pilot._first_frame_by = wall.now + pilot.timeouts.first_frame_s
    assert not _silence(pilot, wall, 2.0)  # 8 s of the simulator's, within the grace
    assert _silence(pilot, wall, 1.5)
