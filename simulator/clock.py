"""Sim time: real elapsed time times the speed-up, or driven by hand in tests."""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Protocol

MAX_SPEEDUP = 100.0


class Clock(Protocol):
    def now(self) -> float:
        """Sim seconds since the clock started."""
        ...


class SimClock:
    """Sim time = monotonic wall time elapsed since creation times ``speedup``."""

    def __init__(self, speedup: float = 1.0, monotonic: Callable[[], float] = time.monotonic):
        if not 0.0 < speedup <= MAX_SPEEDUP:
            raise ValueError(f"speed-up must be > 0 and <= {MAX_SPEEDUP:g}, got {speedup}")
        self.speedup = speedup
        self._monotonic = monotonic
        self._start = monotonic()

    def now(self) -> float:
        return (self._monotonic() - self._start) * self.speedup


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
