from __future__ import annotations

import math

import pytest

from backend.safety import (
    RULES,
    Geofence,
    GeoPoint,
    InvalidGeofence,
    SafetyRails,
    Violation,
    check_arm,
    check_goto,
    check_plan,
    check_takeoff,
    evaluate_plan,
    haversine_m,
)
from backend.safety.mission_waypoints import Waypoint
from tests.unit.safety.shapes import UNKNOWN, geo, north_of, u_fence, vehicle, wp


def rules(violations: list[Violation]) -> list[str]:
    return [v.rule for v in violations]


def only(violations: list[Violation], rule: str) -> Violation:
    matching = [v for v in violations if v.rule == rule]
    assert len(matching) == 1, violations
    return matching[0]


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


# --- Plans ----------------------------------------------------------------------------------


def test_plan_reports_each_rule_once_naming_the_worst_waypoint() -> None:
    rails = SafetyRails(
        geofence=u_fence(max_altitude_m=100),
        max_distance_from_home_m=250,
        min_altitude_m=10,
        max_altitude_m=120,
    )
    waypoints = [
        wp(50, 100, 130),
        wp(50, 250, 160),  # highest
        wp(250, 250, 5),  # lowest; the leg here from waypoint 2 crosses the notch
        wp(250, 50, 3),
        wp(150, 250, 50),  # in the notch
        wp(300, 700, 50),  # 400 m outside, farthest from home
    ]
    violations = check_plan(rails, vehicle(battery=100), waypoints)
    assert rules(violations) == [
        "max_altitude",
        "geofence_max_altitude",
        "min_altitude",
        "geofence",
        "max_distance_from_home",
    ]
    by_rule = {v.rule: v for v in violations}
    assert by_rule["max_altitude"].message == (
        "waypoint 2 altitude 160.0 m is above the 120.0 m ceiling (2 waypoints are above it)"
    )
    assert by_rule["geofence_max_altitude"].message == (
        "waypoint 2 altitude 160.0 m is above the geofence's 100.0 m ceiling "
        "(2 waypoints are above it)"
    )
    assert by_rule["min_altitude"].message == (
        "waypoint 4 altitude 3.0 m is below the 10.0 m floor (2 waypoints are below it)"
    )
    assert by_rule["geofence"].message == (
        "waypoint 6 is 400 m outside the geofence (2 waypoints are outside it); "
        "1 leg between waypoints inside it also leaves it"
    )
    distance = haversine_m(*_latlon(geo(50, 50)), *_latlon(geo(300, 700)))
    assert by_rule["max_distance_from_home"].message == (
        f"waypoint 6 is {distance:.0f} m from home; the limit is 250 m (2 waypoints are beyond it)"
    )
    assert by_rule["max_distance_from_home"].value == pytest.approx(distance)


def _latlon(p: GeoPoint) -> tuple[float, float]:
    return p.lat, p.lon


def test_plan_leg_across_the_notch() -> None:
    violations = check_plan(
        SafetyRails(geofence=u_fence()),
        vehicle(battery=100),
        [wp(50, 250, 30), wp(250, 250, 30), wp(250, 50, 30)],
    )
    assert violations == [
        Violation("geofence", "the leg from waypoint 1 to waypoint 2 leaves the geofence")
    ]


def _item(east: float, north: float, alt: float, item: int) -> Waypoint:
    p = geo(east, north)
    return Waypoint(p.lat, p.lon, alt, item)


def test_plan_violations_list_the_items_at_fault() -> None:
    """An editor shows each refusal on its items: a leg by the item it flies to."""
    rails = SafetyRails(
        geofence=u_fence(), max_distance_from_home_m=250, min_altitude_m=10, max_altitude_m=120
    )
    waypoints = [
        _item(50, 250, 30, 2),  # item 1 is a take-off, with no place of its own here
        _item(250, 250, 30, 3),  # the leg from item 2 crosses the notch; 283 m from home
        _item(250, 50, 130, 4),  # above the ceiling
        _item(300, 700, 5, 6),  # outside, too far and too low
    ]
    by_rule = {v.rule: v for v in check_plan(rails, vehicle(battery=100), waypoints)}
    assert by_rule["geofence"].items == (6, 3)
    assert by_rule["max_altitude"].items == (4,)
    assert by_rule["min_altitude"].items == (6,)
    assert by_rule["max_distance_from_home"].items == (3, 6)  # 283 m and 660 m from home
    # A rule about the vehicle names no item.
    low = check_plan(SafetyRails(min_launch_battery_pct=50), vehicle(battery=20), waypoints[:1])
    assert only(low, "min_launch_battery").items == ()


def test_plan_first_leg_starts_at_the_vehicle() -> None:
    [violation] = check_plan(
        SafetyRails(geofence=u_fence()), vehicle(at=geo(250, 250), battery=100), [wp(50, 250, 30)]
    )
    assert violation.message == (
        "the leg from the vehicle's position to waypoint 1 leaves the geofence"
    )


def test_plan_inside_the_rails_is_allowed() -> None:
    rails = SafetyRails(
        geofence=u_fence(max_altitude_m=100),
        max_distance_from_home_m=400,
        min_altitude_m=10,
        max_altitude_m=120,
        min_launch_battery_pct=30,
    )
    route = [wp(50, 250, 30), wp(50, 50, 40), wp(250, 50, 40), wp(250, 250, 40)]
    check = evaluate_plan(rails, vehicle(), route)
    assert check.ok
    assert check.violations == ()
    assert check.estimate is not None


def test_plan_battery_rules() -> None:
    rails = SafetyRails(min_launch_battery_pct=30)
    far = [wp(0, 0, 30), wp(0, 5000, 30)]
    violations = check_plan(rails, vehicle(battery=25), far)
    assert rules(violations) == ["min_launch_battery", "battery_sufficiency"]
    sufficiency = only(violations, "battery_sufficiency")
    assert sufficiency.limit == 25
    assert sufficiency.message.startswith("mission needs about ")
    assert sufficiency.message.endswith("% of the battery plus a 20% reserve; 25% remains")


def test_plan_with_nothing_known_fails_closed_in_one_violation() -> None:
    rails = SafetyRails(geofence=u_fence(), max_distance_from_home_m=500, min_launch_battery_pct=30)
    check = evaluate_plan(rails, UNKNOWN, [wp(50, 250, 30)])
    assert check.estimate is None
    assert check.violations == (
        Violation(
            "position_unknown",
            "cannot check geofence, max_distance_from_home, min_launch_battery and "
            "battery_sufficiency: the vehicle's position, home position and battery level "
            "are not known",
        ),
    )


def test_plan_needs_the_altitude_of_a_flying_vehicle() -> None:
    flying = vehicle(alt=None, landed=False)
    [violation] = check_plan(SafetyRails(), flying, [wp(50, 250, 30)])
    assert violation.message == (
        "cannot check battery_sufficiency: the vehicle's altitude is not known"
    )


def test_plan_rejects_bad_input() -> None:
    with pytest.raises(ValueError, match="at least one waypoint"):
        check_plan(SafetyRails(), vehicle(), [])
    with pytest.raises(ValueError, match="waypoint 2 altitude nan"):
        check_plan(SafetyRails(), vehicle(), [wp(0, 0, 10), wp(0, 0, math.nan)])


# --- Rails ----------------------------------------------------------------------------------


def test_merged_rails_take_vehicle_values_where_set() -> None:
    site = SafetyRails(
        geofence=u_fence(),
        max_distance_from_home_m=500,
        max_altitude_m=120,
        min_launch_battery_pct=30,
        battery_reserve_pct=25,
    )
    own_fence = Geofence((geo(0, 0), geo(10, 0), geo(0, 10)))
    merged = site.merged_with(SafetyRails(geofence=own_fence, max_altitude_m=60))
    assert merged == SafetyRails(
        geofence=own_fence,
        max_distance_from_home_m=500,
        max_altitude_m=60,
        min_launch_battery_pct=30,
        battery_reserve_pct=25,
    )
    assert site.merged_with(SafetyRails(battery_reserve_pct=35)).battery_reserve_pct == 35
    assert site.merged_with(None) is site
    assert SafetyRails().merged_with(SafetyRails(min_altitude_m=5)).min_altitude_m == 5


def test_rails_refuse_limits_that_would_pass_everything() -> None:
    with pytest.raises(ValueError, match="max_altitude_m nan"):
        SafetyRails(max_altitude_m=math.nan)
    with pytest.raises(ValueError, match="battery_reserve_pct 120"):
        SafetyRails(battery_reserve_pct=120)
    with pytest.raises(InvalidGeofence, match="max_altitude_m -1"):
        Geofence((geo(0, 0), geo(10, 0), geo(0, 10)), max_altitude_m=-1)


def test_geofence_validates_its_polygon() -> None:
    with pytest.raises(InvalidGeofence, match="edges 1 and 3 cross"):
        Geofence((geo(0, 0), geo(100, 100), geo(100, 0), geo(0, 100)))
    closed = Geofence((geo(0, 0), geo(10, 0), geo(0, 10), geo(0, 0)))
    assert len(closed.polygon) == 3
    assert closed == Geofence((geo(0, 0), geo(10, 0), geo(0, 10)))
    assert hash(closed) == hash(Geofence((geo(0, 0), geo(10, 0), geo(0, 10))))


def test_rule_names_are_stable() -> None:
    assert RULES == (
        "geofence",
        "geofence_max_altitude",
        "max_altitude",
        "min_altitude",
        "min_height_above_home",
        "max_distance_from_home",
        "min_launch_battery",
        "battery_sufficiency",
        "home_altitude",
        "position_unknown",
        "mission_item",
        "mission_unchecked",
    )
