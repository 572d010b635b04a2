"""Sliding-window rate limits, per key (an address, a username, a user)."""

from __future__ import annotations

import collections
import math
import time
from collections.abc import Callable
from dataclasses import dataclass

from backend.errors import RateLimited


@dataclass(frozen=True)
class Limit:
    events: int
    per_s: float


def whole_seconds(wait_s: float) -> int:
    """A wait as Retry-After gives it: whole seconds, rounded up, at least 1."""
    return max(1, math.ceil(wait_s))


class RateLimiter:
    def __init__(self, limit: Limit, clock: Callable[[], float] = time.monotonic) -> None:
        self.limit = limit
        self._clock = clock
        self._events: dict[str, collections.deque[float]] = collections.defaultdict(
            collections.deque
        )

    def _window(self, key: str) -> collections.deque[float]:
        events = self._events[key]
        horizon = self._clock() - self.limit.per_s
        while events and events[0] <= horizon:
            events.popleft()
        return events

    def check(self, key: str, what: str) -> None:
        """Raise RateLimited if ``key`` has used up its budget (does not count an event)."""
        events = self._window(key)
        if len(events) >= self.limit.events:
            retry_after = events[0] + self.limit.per_s - self._clock()
            # In whole seconds, rounded up as the Retry-After header is: "try again in
            # 0 s" read as "now", and now was still refused.
            raise RateLimited(
                f"too many {what}; try again in {whole_seconds(retry_after)} s", retry_after
            )

    def hit(self, key: str, count: int = 1) -> None:
        """Count ``count`` events now (a group command counts each vehicle it reaches)."""
        now = self._clock()
        self._window(key).extend([now] * count)
        if len(self._events) > 10_000:
            # Forget idle keys so an address scan cannot grow this without bound.
            for idle in [k for k, v in self._events.items() if not v]:
                del self._events[idle]

    def reset(self, key: str) -> None:
        self._events.pop(key, None)

    def forget_one(self, key: str) -> None:
        """Take back the newest event of ``key`` (an attempt that turned out fine)."""
        events = self._events.get(key)
        if events:
            events.pop()
