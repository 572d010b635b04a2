"""The agent's waits run at the autopilot's pace, and never slower than the wall clock:
a sped-up simulator's failsafes fire in its seconds, a stalled autopilot clock's in ours."""

from __future__ import annotations

import asyncio
import time

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from tests.support.paced import FakeWall, fcu_at
from vehicle_agents.sensors.paced_clock import PacedClock


def test_before_the_autopilot_is_heard_the_wall_clock_paces() -> None:
    wall = FakeWall()
    clock = PacedClock(monotonic=wall)
    start = clock()
    wall.now += 2.0
    assert clock() - start == 2.0


def test_a_sped_up_autopilot_paces_the_waits() -> None:
    wall = FakeWall()
    clock = PacedClock(fcu_at(4.0), monotonic=wall)
    assert abs(clock.pace - 4.0) < 0.01
    start = clock()
    wall.now += 0.5
    assert abs((clock() - start) - 2.0) < 0.01


def test_a_stalled_or_slow_autopilot_clock_never_slows_a_wait_below_the_wall() -> None:
    for rate in (0.0, 0.5):
        wall = FakeWall()
        clock = PacedClock(fcu_at(rate), monotonic=wall)
        assert clock.pace == 1.0
        start = clock()
        wall.now += 3.0
        assert clock() - start >= 3.0


def test_the_autopilots_stamps_set_the_pace() -> None:
    wall = FakeWall()
    clock = PacedClock(monotonic=wall)
    for i in range(1, 61):  # 6 s of a 10 Hz stream: the pace is fitted every 20 stamps
        wall.now += 0.1
        clock.on_message(mavlink2.MAVLink_attitude_message(int(400 * i), 0, 0, 0, 0, 0, 0))
        clock.on_message(mavlink2.MAVLink_heartbeat_message(2, 3, 0, 0, 0, 3))  # no stamp
    assert abs(clock.pace - 4.0) < 0.01


def test_a_wait_is_cut_short_by_its_event_and_otherwise_lasts_its_paced_time() -> None:
    async def run() -> tuple[bool, bool, float]:
        clock = PacedClock(fcu_at(4.0))  # the real wall clock, paced 4x
        event = asyncio.Event()
        asyncio.get_running_loop().call_later(0.05, event.set)
        set_in_time = await clock.wait(event, 10.0)
        started = time.monotonic()
        timed_out = not await clock.wait(asyncio.Event(), 0.8)
        return set_in_time, timed_out, time.monotonic() - started

    set_in_time, timed_out, took = asyncio.run(run())
    assert set_in_time
    assert timed_out
    assert 0.15 <= took < 0.8  # 0.8 s of a 4x autopilot: 0.2 s of ours, never the 0.8
