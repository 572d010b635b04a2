"""The mission rails: every waypoint and leg of a plan against the rails, each rule once."""

from __future__ import annotations

import math

import pytest

from backend.safety import (
    GeoPoint,
    SafetyRails,
    Violation,
    Waypoint,
    check_plan,
    evaluate_plan,
    haversine_m,
)
from tests.unit.safety.shapes import UNKNOWN, geo, only, rules, u_fence, vehicle, wp

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
