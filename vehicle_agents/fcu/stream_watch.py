"""Watching the rate each requested message actually arrives at.

A flight controller keeps one set of rates per link, and a second GCS on the same link
(MAVProxy or QGroundControl attached through forwarding) sets its own: MAVProxy's
REQUEST_DATA_STREAM at 4 Hz overrides ArduPilot's per-message intervals, and the agent's
10 Hz position became 4 Hz unnoticed. So each message asked for is counted as it comes,
and one that falls below the rate asked for is named, to be asked for again.

Asking again backs off (one window, then twice that, up to ``retry_max_s``), so a link
that cannot carry the rate (a slow radio) or a GCS that keeps resetting it is not fought
at full speed; the fall and the recovery are each logged once. A message that has not
arrived since the rates were set is not judged: the vehicle may not have it (no second
GPS). The clock is injected, so tests drive time.
"""

from __future__ import annotations

import logging
from collections import deque
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

from vehicle_agents.fcu.messages import MavMessage

if TYPE_CHECKING:
    from vehicle_agents.fcu.stream_plan import StreamRequest

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class RateWatchSettings:
    window_s: float = 5.0  # the achieved rate is measured over this ...
    min_expected: int = 5  # ... or over this many periods of a slow message, if longer
    slow_below: float = 0.75  # achieved / asked under this is too slow (jitter stays above)
    retry_max_s: float = 60.0


@dataclass
class _Watched:
    request: StreamRequest
    window_s: float
    judge_from: float  # no verdict before this: the rate asked for has had a window to take
    arrivals: deque[float] = field(default_factory=deque)
    backoff_s: float = 0.0
    seen: bool = False  # arrived since the rates were set: the vehicle has it
    slow: bool = False  # reported slow, not yet recovered

    def achieved_hz(self, now: float) -> float:
        while self.arrivals and self.arrivals[0] <= now - self.window_s:
            self.arrivals.popleft()
        return len(self.arrivals) / self.window_s


class RateWatch:
    """Counts arrivals of the watched messages; ``due`` names those to ask for again."""

    def __init__(self, settings: RateWatchSettings, clock: Callable[[], float]) -> None:
        self.settings = settings
        self.clock = clock
        self._watched: dict[str, _Watched] = {}
        self.rerequests = 0  # how many times a message was asked for again

    def watch(self, requests: Iterable[StreamRequest]) -> None:
        """Start over with these (the rates were just set): nothing judged for a window."""
        now = self.clock()
        self._watched = {}
        for request in requests:
            if request.rate_hz <= 0:
                continue
            window = max(self.settings.window_s, self.settings.min_expected / request.rate_hz)
            self._watched[request.message] = _Watched(
                request, window, now + window, deque(), window
            )

    def on_message(self, message: MavMessage) -> None:
        watched = self._watched.get(message.get_type())
        if watched is not None:
            watched.arrivals.append(self.clock())
            watched.seen = True

    def achieved_hz(self, message: str) -> float | None:
        watched = self._watched.get(message)
        return None if watched is None else watched.achieved_hz(self.clock())

    def due(self) -> list[StreamRequest]:
        """The messages arriving too slowly to ask for again now."""
        now = self.clock()
        again = []
        for name, watched in self._watched.items():
            if now < watched.judge_from or not watched.seen:
                continue
            achieved = watched.achieved_hz(now)
            asked = watched.request.rate_hz
            if achieved >= self.settings.slow_below * asked:
                if watched.slow:
                    log.info("%s back at %.1f Hz (%g Hz asked for)", name, achieved, asked)
                    watched.slow = False
                    watched.backoff_s = watched.window_s
                continue
            level = logging.DEBUG if watched.slow else logging.WARNING
            log.log(
                level,
                "%s arrives at %.1f Hz, %g Hz asked for (another GCS on the link may have "
                "set its own rates); asking again",
                name,
                achieved,
                asked,
            )
            watched.slow = True
            watched.judge_from = now + watched.backoff_s
            watched.backoff_s = min(watched.backoff_s * 2, self.settings.retry_max_s)
            self.rerequests += 1
            again.append(watched.request)
        return again
