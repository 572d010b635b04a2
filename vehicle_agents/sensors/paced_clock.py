"""The clock the agent's waits run on: the autopilot's pace, never slower than the wall.

A failsafe's timeout, the deadman's silence, a formation's stale leader and the hub
link's reconnect waits are all about the aircraft: how far it flies on a stale input,
how long it goes without its ground station. A real board's clock runs with the wall
clock, so there the two are one; a simulator at ``--speedup`` 4 flies four seconds in
one of the wall's, and its vehicles must be failsafed in its seconds, not ours.

The pace is the slope `FcuClock` fits through the flight controller's stamps (1 for a
real board). Each reading advances by the wall time since the last one times
``max(1, pace)``, so any elapsed time measured on it is at least the wall's and at least
the autopilot's (``elapsed >= max(wall elapsed, autopilot elapsed)``): a wait on it is
never longer than the same wait on the wall clock. That is the safety rule. When the
autopilot's clock stalls (its link lost, the board frozen, a clock that stopped
counting), no new slope is fitted, or a slope below 1 is, and the wait runs at least on
the wall clock: a failsafe then fires at the earlier of the two, never later.
"""

from __future__ import annotations

import asyncio
import contextlib
import time
from collections.abc import Callable
from typing import Any

from vehicle_agents.sensors.fcu_time import STAMPED, FcuClock

MAX_PACE = 100.0  # the simulator's own limit; a wilder fit is a bad fit, not a clock
POLL_S = 0.1  # the most a wait sleeps before it reads the pace again (wall seconds)


class PacedClock:
    """Monotonic seconds at the autopilot's pace, never slower than the wall clock."""

    def __init__(
        self, fcu: FcuClock | None = None, monotonic: Callable[[], float] = time.monotonic
    ) -> None:
        self.fcu = fcu or FcuClock()
        self._monotonic = monotonic
        self._wall = monotonic()
        self._now = self._wall

    @property
    def pace(self) -> float:
        """Autopilot seconds per wall second, at least 1."""
        return min(MAX_PACE, max(1.0, self.fcu.rate))

    def __call__(self) -> float:
        wall = self._monotonic()
        self._now += max(0.0, wall - self._wall) * self.pace
        self._wall = wall
        return self._now

    def on_message(self, message: Any) -> None:
        """An FcuLink listener: the flight controller's stamps, for its pace."""
        if message.get_type() not in STAMPED:
            return
        boot_s = message.time_boot_ms / 1000.0
        if boot_s > 0.0:  # SYSTEM_TIME before the board's clock is known
            self.fcu.add(self._monotonic(), boot_s)

    async def sleep(self, seconds: float) -> None:
        """Until ``seconds`` have passed on this clock (at most that long on the wall)."""
        await self.wait(asyncio.Event(), seconds)  # an event never set

    async def wait(self, event: asyncio.Event, seconds: float) -> bool:
        """Whether ``event`` was set within ``seconds`` of this clock."""
        end = self() + seconds
        while not event.is_set():
            left = end - self()
            if left <= 0:
                return False
            with contextlib.suppress(TimeoutError):
                async with asyncio.timeout(min(left / self.pace, POLL_S)):
                    await event.wait()
        return True
