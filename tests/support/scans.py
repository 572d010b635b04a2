"""Scan frames as an agent sends them, for the tests of the hub's scan path."""

from __future__ import annotations

import math

from protocol.scans import (
    Mount,
    ScanFrame,
    ScanPose,
    quantise,
)


def _frame(beams: int = 720) -> ScanFrame:
    ranges, _ = quantise([1.0 + i * 0.01 for i in range(beams)], 0.001, 12.0)
    return ScanFrame(
        seq=41,
        sensor_time_us=123_456_789,
        utc_time=1_760_000_000.25,
        duration_s=0.1,
        angle_min=0.0,
        angle_increment=-math.radians(0.5),
        range_max_m=12.0,
        pose_start=ScanPose(-35.363262, 149.165237, 589.0, 0.01, -0.02, 1.5),
        pose_end=ScanPose(-35.3632621, 149.1652371, 589.1, 0.01, -0.02, 1.6),
        ranges=ranges,
        mount=Mount(0.05, 0.0, -0.1, 0.0, 0.0, math.pi),
    )
