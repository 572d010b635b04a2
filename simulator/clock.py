"""Sim time: real elapsed time times the speed-up, or driven by hand in tests."""

from __future__ import annotations

import threading
import time
from collections.abc import Callable
from typing import Protocol

MAX_SPEEDUP = 100.0


class Clock(Protocol):
    def now(self) -> float:
        """Sim seconds since the clock started."""
        ...


class SimClock:
    """Sim time = monotonic wall time elapsed since creation times ``speedup``.

    With ``max_step_s``, the clock holds through a stall as SITL's lockstep does: of the
    wall time between two readings, no more than ``max_step_s`` counts, so a process held
    up for tenths of a second (a busy machine) loses that time rather than its streams
    jumping ahead of what was sent. It is read from several threads.
    """

    def __init__(
        self,
        speedup: float = 1.0,
        monotonic: Callable[[], float] = time.monotonic,
        max_step_s: float | None = None,
    ):
        if not 0.0 < speedup <= MAX_SPEEDUP:
            raise ValueError(f"speed-up must be > 0 and <= {MAX_SPEEDUP:g}, got {speedup}")
        self.speedup = speedup
        self._monotonic = monotonic
        self._max_step_s = max_step_s
        self._lock = threading.Lock()
        self._read_at = monotonic()
        self._now = 0.0

    def now(self) -> float:
        with self._lock:
            wall = self._monotonic()
            step = wall - self._read_at
            if self._max_step_s is not None:
                step = min(step, self._max_step_s)
            self._read_at = wall
            self._now += step * self.speedup
            return self._now


class ManualClock:
    """A clock that moves only when told to."""

    def __init__(self, start: float = 0.0) -> None:
        self._now = start

    def now(self) -> float:
        return self._now

    def advance(self, seconds: float) -> None:
        if seconds < 0.0:
            raise ValueError("time does not run backwards")
        self._now += seconds
