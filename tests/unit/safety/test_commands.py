"""The command rails: arm, take-off and go-to against the rails (a new home:
`test_cmd_set_home_rails`)."""

from __future__ import annotations

import math

import pytest

from backend.safety import (
    GeoPoint,
    SafetyRails,
    Violation,
    check_arm,
    check_goto,
    check_takeoff,
)
from tests.unit.safety.shapes import UNKNOWN, geo, north_of, only, rules, u_fence, vehicle

# --- Arm ------------------------------------------------------------------------------------


def test_arm_refused_below_launch_battery() -> None:
    rails = SafetyRails(min_launch_battery_pct=30)
    [violation] = check_arm(rails, vehicle(battery=18))
    assert violation == Violation(
        "min_launch_battery", "battery 18% is below the 30% needed to launch", 30, 18
    )
    assert check_arm(rails, vehicle(battery=30)) == []


def test_launch_battery_close_to_the_limit_shows_the_difference() -> None:
    [violation] = check_arm(SafetyRails(min_launch_battery_pct=30), vehicle(battery=29.8))
    assert violation.message == "battery 29.8% is below the 30.0% needed to launch"


def test_launch_battery_only_applies_on_the_ground() -> None:
    rails = SafetyRails(min_launch_battery_pct=30)
    assert check_arm(rails, vehicle(battery=10, landed=False)) == []


def test_arm_with_unknown_battery_fails_closed_only_when_a_rule_needs_it() -> None:
    [violation] = check_arm(SafetyRails(min_launch_battery_pct=30), vehicle(battery=None))
    assert violation.rule == "position_unknown"
    assert violation.message == (
        "cannot check min_launch_battery: the vehicle's battery level is not known"
    )
    assert check_arm(SafetyRails(min_launch_battery_pct=30), vehicle(battery=math.nan)) != []
    assert check_arm(SafetyRails(), UNKNOWN) == []


# --- Take-off -------------------------------------------------------------------------------


def test_takeoff_above_the_ceiling() -> None:
    [violation] = check_takeoff(SafetyRails(max_altitude_m=120), vehicle(), 150)
    assert violation == Violation(
        "max_altitude", "take-off altitude 150.0 m is above the 120.0 m ceiling", 120, 150
    )


def test_takeoff_below_the_floor() -> None:
    [violation] = check_takeoff(SafetyRails(min_altitude_m=10), vehicle(), 2.5)
    assert violation.rule == "min_altitude"
    assert violation.message == "take-off altitude 2.5 m is below the 10.0 m floor"


def test_takeoff_lists_every_violation_together() -> None:
    rails = SafetyRails(
        geofence=u_fence(max_altitude_m=100), max_altitude_m=120, min_launch_battery_pct=30
    )
    outside = vehicle(at=geo(150, 250), battery=20)
    violations = check_takeoff(rails, outside, 150)
    assert rules(violations) == [
        "min_launch_battery",
        "max_altitude",
        "geofence_max_altitude",
        "geofence",
    ]
    assert only(violations, "geofence_max_altitude").message == (
        "take-off altitude 150.0 m is above the geofence's 100.0 m ceiling"
    )
    fence = only(violations, "geofence")
    assert fence.message == "vehicle is 50 m outside the geofence"
    assert fence.value == pytest.approx(50, abs=0.01)


def test_takeoff_inside_the_fence_is_allowed() -> None:
    rails = SafetyRails(geofence=u_fence(100), max_altitude_m=120, min_altitude_m=5)
    assert check_takeoff(rails, vehicle(), 20) == []


def test_takeoff_with_unknown_position_fails_closed() -> None:
    [violation] = check_takeoff(SafetyRails(geofence=u_fence()), UNKNOWN, 20)
    assert violation.rule == "position_unknown"
    assert "geofence" in violation.message
    assert "position is not known" in violation.message
    assert check_takeoff(SafetyRails(max_altitude_m=120), UNKNOWN, 20) == []


def test_zero_zero_is_no_position_for_the_rails() -> None:
    """ArduPilot's GLOBAL_POSITION_INT before its EKF has an origin, if an agent passed it
    on: the rails fail closed instead of measuring from the Gulf of Guinea."""
    null_island = GeoPoint(0.0, 0.0)
    [violation] = check_takeoff(SafetyRails(geofence=u_fence()), vehicle(null_island), 20)
    assert violation.rule == "position_unknown"
    target = geo(60, 60)
    rails = SafetyRails(max_distance_from_home_m=500)
    assert check_goto(rails, vehicle(geo(50, 50)), target.lat, target.lon, 20) == []
    [violation] = check_goto(
        rails, vehicle(geo(50, 50), home=null_island), target.lat, target.lon, 20
    )
    assert violation.rule == "position_unknown"


# --- Go to ----------------------------------------------------------------------------------


def test_goto_beyond_the_range_from_home() -> None:
    home = geo(50, 50)
    target = north_of(home, 812)
    [violation] = check_goto(
        SafetyRails(max_distance_from_home_m=500), vehicle(), target.lat, target.lon, 30
    )
    assert violation.rule == "max_distance_from_home"
    assert violation.message == "target is 812 m from home; the limit is 500 m"
    assert violation.limit == 500
    assert violation.value == pytest.approx(812)


def test_goto_target_outside_the_fence() -> None:
    target = geo(150, 250)
    [violation] = check_goto(SafetyRails(geofence=u_fence()), vehicle(), target.lat, target.lon, 30)
    assert violation.rule == "geofence"
    assert violation.message == "target is 50 m outside the geofence"


def test_goto_across_the_notch_is_refused_although_both_ends_are_inside() -> None:
    rails = SafetyRails(geofence=u_fence())
    target = geo(250, 250)
    [violation] = check_goto(rails, vehicle(at=geo(50, 250)), target.lat, target.lon, 30)
    assert violation.rule == "geofence"
    assert "straight leg" in violation.message
    # The same target is fine from the base of the U.
    assert check_goto(rails, vehicle(at=geo(250, 50)), target.lat, target.lon, 30) == []


def test_goto_back_into_the_fence_is_allowed_from_outside() -> None:
    target = geo(50, 50)
    outside = vehicle(at=geo(150, 250))
    assert check_goto(SafetyRails(geofence=u_fence()), outside, target.lat, target.lon, 30) == []


def test_goto_lists_every_violation_together() -> None:
    rails = SafetyRails(
        geofence=u_fence(max_altitude_m=100),
        max_distance_from_home_m=100,
        min_altitude_m=200,
        max_altitude_m=120,
    )
    target = geo(150, 250)
    violations = check_goto(rails, vehicle(), target.lat, target.lon, 150)
    assert rules(violations) == [
        "max_altitude",
        "geofence_max_altitude",
        "min_altitude",
        "geofence",
        "max_distance_from_home",
    ]
    assert all(v.message for v in violations)


def test_goto_with_unknown_position_and_home_fails_closed() -> None:
    rails = SafetyRails(geofence=u_fence(), max_distance_from_home_m=500)
    target = geo(50, 250)
    [violation] = check_goto(rails, UNKNOWN, target.lat, target.lon, 30)
    assert violation == Violation(
        "position_unknown",
        "cannot check geofence and max_distance_from_home: "
        "the vehicle's position and home position are not known",
    )


def test_goto_with_nan_is_an_error_not_a_pass() -> None:
    rails = SafetyRails(max_altitude_m=120)
    with pytest.raises(ValueError, match="altitude nan"):
        check_goto(rails, vehicle(), 47.0, 8.0, math.nan)
    with pytest.raises(ValueError, match="not a valid latitude"):
        check_goto(rails, vehicle(), math.nan, 8.0, 30)
    with pytest.raises(ValueError, match="not a finite number"):
        check_takeoff(rails, vehicle(), math.inf)
