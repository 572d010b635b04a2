"""Tracking metrics on the hub: live error, RMS and maximum per leg and per mission."""

from __future__ import annotations

import math

import pytest

from backend.formation.metrics import TrackingMetrics


def test_errors_are_kept_per_leg_and_over_the_mission_legs_only() -> None:
    metrics = TrackingMetrics()
    metrics.record("f1", 1.0, (0.3, 0.4, -0.1), leg=1)  # 0.5 m horizontal
    metrics.record("f1", 1.1, (0.0, 0.1, 0.2), leg=1)
    metrics.record("f1", 1.2, (3.0, 4.0, 0.0), leg=None)  # a corner's pause: live only
    metrics.record("f1", 1.3, (0.0, -1.0, 0.0), leg=2)
    tracking = metrics.followers["f1"]
    assert tracking.live_xy_m == pytest.approx(1.0)
    assert tracking.live_z_m == pytest.approx(0.0)
    leg1 = tracking.legs[1]
    assert leg1.samples == 2
    assert leg1.rms_xy_m == pytest.approx(math.sqrt((0.25 + 0.01) / 2))
    assert leg1.max_xy_m == pytest.approx(0.5)
    assert leg1.max_z_m == pytest.approx(0.2)
    assert tracking.mission.samples == 3
    assert tracking.mission.max_xy_m == pytest.approx(1.0)  # not the pause's 5 m
    assert tracking.mission.rms_xy_m == pytest.approx(math.sqrt((0.25 + 0.01 + 1.0) / 3))


def test_a_report_is_sampled_once() -> None:
    """The hub relays at 10 Hz whether or not a follower has reported since."""
    metrics = TrackingMetrics()
    metrics.record("f1", 5.0, (1.0, 0.0, 0.0), leg=1)
    metrics.record("f1", 5.0, (1.0, 0.0, 0.0), leg=1)
    assert metrics.followers["f1"].mission.samples == 1
    assert metrics.followers["f1"].mission.rms_z_m == 0.0
