"""The leader's route in time: straight legs at a constant speed, with a pause at each
waypoint. A virtual leader is this and nothing more; a vehicle leader flies the same
route as a mission, and the followers take its reported state instead."""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from dataclasses import dataclass

from common.formation import LeaderState


@dataclass(frozen=True)
class Leg:
    start_s: float  # when the leg begins (after the pause at its start)
    start: tuple[float, float, float]  # north, east, up
    end: tuple[float, float, float]
    duration_s: float

    @property
    def heading_rad(self) -> float:
        return math.atan2(self.end[1] - self.start[1], self.end[0] - self.start[0]) % math.tau


class LeaderRoute:
    """Waypoints (north, east, up metres) flown in order at ``speed_ms``, pausing
    ``pause_s`` at each one, the first included (where the leader starts)."""

    def __init__(
        self, points: Sequence[tuple[float, float, float]], speed_ms: float, pause_s: float
    ) -> None:
        if len(points) < 2:
            raise ValueError("a route needs at least two waypoints")
        if not (math.isfinite(speed_ms) and speed_ms > 0):
            raise ValueError(f"the speed must be positive, not {speed_ms}")
        if not (math.isfinite(pause_s) and pause_s >= 0):
            raise ValueError(f"the pause must be zero or more seconds, not {pause_s}")
        self.points = [(float(n), float(e), float(u)) for n, e, u in points]
        self.speed_ms = speed_ms
        self.pause_s = pause_s
        self.legs: list[Leg] = []
        t = pause_s
        for a, b in itertools.pairwise(self.points):
            duration = math.dist(a[:2], b[:2]) / speed_ms if a != b else 0.0
            duration = max(duration, abs(b[2] - a[2]) / speed_ms)
            self.legs.append(Leg(t, a, b, duration))
            t += duration + pause_s
        self.duration_s = t

    def leg_at(self, t: float) -> int | None:
        """The index of the leg being flown at ``t``; None while paused or done."""
        for i, leg in enumerate(self.legs):
            if leg.start_s <= t < leg.start_s + leg.duration_s:
                return i
        return None

    def state_at(self, t: float) -> LeaderState:
        """Where the leader is, how fast it moves and where it heads at ``t`` seconds."""
        heading = self.legs[0].heading_rad
        for leg in self.legs:
            if t < leg.start_s:
                # pausing at the leg's start, already facing along it
                north, east, up = leg.start
                return LeaderState(north, east, up, 0.0, 0.0, 0.0, leg.heading_rad, t)
            heading = leg.heading_rad
            if t < leg.start_s + leg.duration_s:
                f = (t - leg.start_s) / leg.duration_s
                (n0, e0, u0), (n1, e1, u1) = leg.start, leg.end
                d = leg.duration_s
                return LeaderState(
                    n0 + (n1 - n0) * f,
                    e0 + (e1 - e0) * f,
                    u0 + (u1 - u0) * f,
                    (n1 - n0) / d,
                    (e1 - e0) / d,
                    (u1 - u0) / d,
                    heading,
                    t,
                )
        north, east, up = self.points[-1]
        return LeaderState(north, east, up, 0.0, 0.0, 0.0, heading, t)
