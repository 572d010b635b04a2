"""How well each follower keeps its slot, as the hub sees it: the live error, and the
RMS and maximum per leg of the leader's route and over the whole mission.

The error is the follower's distance from its slot around the leader, horizontal and
vertical, with the leader carried forward to the instant of the follower's own report
(each vehicle's report has its own time; pairing them as they arrive would measure the
sampling, not the tracking). Legs only: during a corner's pause the slots swing round
the leader, and the seed's figure, like the integration test's, is for the legs. One
sample per follower report (a relay tick that brings no new report adds nothing).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field


@dataclass
class ErrorStats:
    samples: int = 0
    sum_sq_xy: float = 0.0
    max_xy_m: float = 0.0
    sum_sq_z: float = 0.0
    max_z_m: float = 0.0

    def add(self, xy_m: float, z_m: float) -> None:
        self.samples += 1
        self.sum_sq_xy += xy_m * xy_m
        self.sum_sq_z += z_m * z_m
        self.max_xy_m = max(self.max_xy_m, xy_m)
        self.max_z_m = max(self.max_z_m, z_m)

    @property
    def rms_xy_m(self) -> float:
        return math.sqrt(self.sum_sq_xy / self.samples) if self.samples else 0.0

    @property
    def rms_z_m(self) -> float:
        return math.sqrt(self.sum_sq_z / self.samples) if self.samples else 0.0


@dataclass
class FollowerTracking:
    live_xy_m: float | None = None  # the newest error, legs or not
    live_z_m: float | None = None
    legs: dict[int, ErrorStats] = field(default_factory=dict)  # by leg number, from 1
    mission: ErrorStats = field(default_factory=ErrorStats)
    last_report_s: float | None = None  # the follower report last sampled


class TrackingMetrics:
    def __init__(self) -> None:
        self.followers: dict[str, FollowerTracking] = {}

    def record(
        self,
        follower: str,
        report_s: float,
        error: tuple[float, float, float],
        leg: int | None,
    ) -> None:
        """One error (north, east, up metres, follower minus slot) for the follower's
        report at ``report_s``, on leg ``leg`` (from 1) or None in a pause or before the
        route starts; a report already sampled is skipped."""
        tracking = self.followers.setdefault(follower, FollowerTracking())
        if tracking.last_report_s == report_s:
            return
        tracking.last_report_s = report_s
        xy, z = math.hypot(error[0], error[1]), abs(error[2])
        tracking.live_xy_m, tracking.live_z_m = xy, z
        if leg is None:
            return
        tracking.legs.setdefault(leg, ErrorStats()).add(xy, z)
        tracking.mission.add(xy, z)


def stats_summary(stats: ErrorStats) -> dict[str, float | int]:
    return {
        "samples": stats.samples,
        "rms_xy_m": round(stats.rms_xy_m, 4),
        "max_xy_m": round(stats.max_xy_m, 4),
        "rms_z_m": round(stats.rms_z_m, 4),
        "max_z_m": round(stats.max_z_m, 4),
    }


def tracking_summary(metrics: TrackingMetrics) -> dict[str, object]:
    """The figures as stored with the mission (JSON): per follower, per leg and overall."""
    return {
        follower: {
            "legs": {str(leg): stats_summary(s) for leg, s in sorted(t.legs.items())},
            "mission": stats_summary(t.mission),
        }
        for follower, t in metrics.followers.items()
    }
