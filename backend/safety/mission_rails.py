"""The mission rails: every waypoint and leg of a mission, from the vehicle's position,
against every rail, each rule reported once with its worst offender, and whether the
battery lasts the flight and the return home."""

from __future__ import annotations

import itertools
from collections.abc import Sequence
from dataclasses import dataclass

from backend.safety.geofence import Geofence, outside_message
from backend.safety.limits import (
    check_altitudes,
    check_distance,
    check_launch_battery,
    require_target,
)
from backend.safety.mission_battery import (
    DEFAULT_BATTERY_MODEL,
    BatteryEstimate,
    BatteryModel,
    estimate_plan,
    missing_for_estimate,
)
from backend.safety.mission_waypoints import Waypoint
from backend.safety.rails import SafetyRails
from backend.safety.snapshot import VehicleSnapshot, home, position
from backend.safety.violations import (
    BATTERY_SUFFICIENCY,
    GEOFENCE,
    MAX_DISTANCE_FROM_HOME,
    MIN_HEIGHT_ABOVE_HOME,
    Report,
    Violation,
    count,
    others,
    pair,
)
from common.geodesy import GeoPoint, haversine_m


@dataclass(frozen=True)
class PlanCheck:
    violations: tuple[Violation, ...]
    estimate: BatteryEstimate | None

    @property
    def ok(self) -> bool:
        return not self.violations


def _plan_geofence(
    fence: Geofence, vehicle: VehicleSnapshot, waypoints: Sequence[Waypoint], report: Report
) -> None:
    points = [GeoPoint(wp.lat, wp.lon) for wp in waypoints]
    inside = [fence.contains(p) for p in points]
    outside = [(fence.distance_outside_m(p), i) for i, p in enumerate(points) if not inside[i]]
    here = position(vehicle)
    if here is None:
        report.unknown("position", GEOFENCE)
    # Legs with an end outside are already reported through that end; a first leg from a
    # vehicle outside the fence is allowed so that a mission can bring it back.
    stops: list[tuple[str, GeoPoint | None, bool, int | None]] = [
        ("the vehicle's position", here, here is not None and fence.contains(here), None)
    ]
    stops += [
        (waypoints[i].name(i + 1), p, inside[i], waypoints[i].item) for i, p in enumerate(points)
    ]
    # Each leg is shown on the item it flies to.
    leaving = [
        (f"the leg from {a_label} to {b_label}", b_item)
        for (a_label, a, a_in, _), (b_label, b, b_in, b_item) in itertools.pairwise(stops)
        if a is not None and b is not None and a_in and b_in and fence.leg_leaves(a, b)
    ]
    legs = [label for label, _ in leaving]
    at_fault = [waypoints[i].item for _, i in outside] + [item for _, item in leaving]
    if outside:
        distance, worst = max(outside)
        message = outside_message(waypoints[worst].name(worst + 1), distance)
        message += others(len(outside), "waypoints are outside it")
        if legs:
            verb = "leaves" if len(legs) == 1 else "leave"
            message += f"; {count(len(legs), 'leg')} between waypoints inside it also {verb} it"
        report.add(GEOFENCE, message, None, distance, at_fault)
    elif legs:
        report.add(
            GEOFENCE,
            f"{legs[0]} leaves the geofence{others(len(legs), 'legs leave it')}",
            None,
            None,
            at_fault,
        )


def _height_words(wp: Waypoint, index: int, decimals: int) -> str:
    """Where ``wp`` is, in height above home, in the terms its item was written in."""
    below = wp.alt_rel < 0
    height = f"{abs(wp.alt_rel):.{decimals}f} m {'below' if below else 'above'} home"
    if wp.datum == "terrain":
        return (
            f"{wp.name(index)}: {wp.alt_rel:.{decimals}f} m above terrain, taken as {height} "
            "(the hub has no terrain model)"
        )
    if wp.datum == "sea level" and wp.alt_written is not None:
        home_alt = wp.alt_written - wp.alt_rel
        return (
            f"{wp.name(index)}: {height} ({wp.alt_written:.1f} m above sea level; home is at "
            f"{home_alt:.1f} m)"
        )
    return f"{wp.name(index)}: {height}" + (f" ({wp.alt_rel:.{decimals}f} m)" if below else "")


def _plan_height_above_home(
    rails: SafetyRails, waypoints: Sequence[Waypoint], report: Report
) -> None:
    """Every navigation place but a landing at least the minimum above home: one
    violation naming the lowest, with every item below the minimum."""
    limit = rails.min_height_above_home_m
    if limit is None:
        return
    low = [(wp.alt_rel, i) for i, wp in enumerate(waypoints) if wp.held_above_home]
    low = [(alt, i) for alt, i in low if alt < limit]
    if not low:
        return
    alt, worst = min(low)
    _, bound = pair(alt, limit, 1)
    words = _height_words(waypoints[worst], worst + 1, len(bound.partition(".")[2]))
    report.add(
        MIN_HEIGHT_ABOVE_HOME,
        f"{words}; the rails need at least {bound} m "
        f"above home (min_height_above_home_m){others(len(low), 'waypoints are below it')}",
        limit,
        alt,
        [waypoints[i].item for _, i in sorted(low, key=lambda o: o[1])],
    )


def _plan_distance(
    rails: SafetyRails, vehicle: VehicleSnapshot, waypoints: Sequence[Waypoint], report: Report
) -> None:
    if rails.max_distance_from_home_m is None:
        return
    start = home(vehicle)
    if start is None:
        report.unknown("home position", MAX_DISTANCE_FROM_HOME)
        return
    limit = rails.max_distance_from_home_m
    distances = [haversine_m(start.lat, start.lon, wp.lat, wp.lon) for wp in waypoints]
    far = max(range(len(distances)), key=distances.__getitem__)
    suffix = others(sum(d > limit for d in distances), "waypoints are beyond it")
    beyond = [wp.item for wp, d in zip(waypoints, distances, strict=True) if d > limit]
    check_distance(rails, waypoints[far].name(far + 1), distances[far], suffix, report, beyond)


def _plan_battery(
    rails: SafetyRails,
    vehicle: VehicleSnapshot,
    waypoints: Sequence[Waypoint],
    model: BatteryModel,
    report: Report,
) -> BatteryEstimate | None:
    missing = missing_for_estimate(vehicle)
    for item in missing:
        report.unknown(item, BATTERY_SUFFICIENCY)
    if missing:
        return None
    estimate = estimate_plan(vehicle, waypoints, model)
    available = estimate.available_pct
    needed = estimate.required_pct + rails.battery_reserve_pct
    if available is None:
        report.unknown("battery level", BATTERY_SUFFICIENCY)
    elif needed > available:
        report.add(
            BATTERY_SUFFICIENCY,
            f"mission needs about {estimate.required_pct:.0f}% of the battery plus a "
            f"{rails.battery_reserve_pct:.0f}% reserve; {available:.0f}% remains",
            available,
            needed,
        )
    return estimate


def evaluate_plan(
    rails: SafetyRails,
    vehicle: VehicleSnapshot,
    waypoints: Sequence[Waypoint],
    model: BatteryModel = DEFAULT_BATTERY_MODEL,
) -> PlanCheck:
    """check_plan's violations together with the battery estimate (None when the vehicle's
    position, home or altitude is not known)."""
    if not waypoints:
        raise ValueError("a mission needs at least one waypoint")
    for i, wp in enumerate(waypoints, start=1):
        require_target(wp.name(i), wp.lat, wp.lon, wp.alt_rel)
    report = Report()
    check_launch_battery(rails, vehicle, report)
    check_altitudes(
        rails,
        [(f"{wp.name(i)} altitude", wp.alt_rel) for i, wp in enumerate(waypoints, 1)],
        report,
        [wp.item for wp in waypoints],
    )
    _plan_height_above_home(rails, waypoints, report)
    if rails.geofence is not None:
        _plan_geofence(rails.geofence, vehicle, waypoints, report)
    _plan_distance(rails, vehicle, waypoints, report)
    estimate = _plan_battery(rails, vehicle, waypoints, model, report)
    return PlanCheck(tuple(report.violations()), estimate)


def check_plan(
    rails: SafetyRails,
    vehicle: VehicleSnapshot,
    waypoints: Sequence[Waypoint],
    model: BatteryModel = DEFAULT_BATTERY_MODEL,
) -> list[Violation]:
    """Every waypoint and leg (from the vehicle's position) against every rule, each rule
    reported once with its worst offender."""
    return list(evaluate_plan(rails, vehicle, waypoints, model).violations)
