"""The rules that hold one value against one limit, shared by the command and the mission
rails: the battery needed to launch, the altitude floor and ceilings, the range from home.

Inputs are assumed range-checked by the caller (the API schemas do that); the checks still
refuse NaN and infinities outright, because a NaN compares false against every limit and
would otherwise pass them all.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

from backend.safety.rails import SafetyRails
from backend.safety.snapshot import VehicleSnapshot, known
from backend.safety.violations import (
    GEOFENCE_MAX_ALTITUDE,
    MAX_ALTITUDE,
    MAX_DISTANCE_FROM_HOME,
    MIN_ALTITUDE,
    MIN_LAUNCH_BATTERY,
    Report,
    others,
    pair,
)


def require_target(what: str, lat: float, lon: float, alt: float) -> None:
    if not (math.isfinite(lat) and -90 <= lat <= 90 and math.isfinite(lon) and -180 <= lon <= 180):
        raise ValueError(f"{what} position ({lat}, {lon}) is not a valid latitude and longitude")
    require_altitude(what, alt)


def require_altitude(what: str, alt: float) -> None:
    if not math.isfinite(alt):
        raise ValueError(f"{what} altitude {alt} is not a finite number")


def check_launch_battery(rails: SafetyRails, vehicle: VehicleSnapshot, report: Report) -> None:
    limit = rails.min_launch_battery_pct
    if limit is None or not vehicle.landed:
        return
    battery = known(vehicle.battery_remaining_pct)
    if battery is None:
        report.unknown("battery level", MIN_LAUNCH_BATTERY)
    elif battery < limit:
        shown, bound = pair(battery, limit, 0)
        report.add(
            MIN_LAUNCH_BATTERY,
            f"battery {shown}% is below the {bound}% needed to launch",
            limit,
            battery,
        )


def _altitude_limits(rails: SafetyRails) -> list[tuple[str, float, bool, str]]:
    """(rule, limit, is a ceiling, how messages name it) for each altitude limit set."""
    limits: list[tuple[str, float, bool, str]] = []
    if rails.max_altitude_m is not None:
        limits.append((MAX_ALTITUDE, rails.max_altitude_m, True, "the {} m ceiling"))
    fence_ceiling = rails.geofence.max_altitude_m if rails.geofence else None
    if fence_ceiling is not None:
        limits.append((GEOFENCE_MAX_ALTITUDE, fence_ceiling, True, "the geofence's {} m ceiling"))
    if rails.min_altitude_m is not None:
        limits.append((MIN_ALTITUDE, rails.min_altitude_m, False, "the {} m floor"))
    return limits


def check_altitudes(
    rails: SafetyRails,
    targets: Sequence[tuple[str, float]],
    report: Report,
    items: Sequence[int | None] = (),
) -> None:
    """Each altitude limit against (label, altitude) targets: one violation per limit,
    naming the target furthest beyond it. ``items``, when given, are the targets' mission
    items (in the same order), listed on each violation."""
    numbers = list(items) or [None] * len(targets)
    for rule, limit, ceiling, name in _altitude_limits(rails):
        beyond = [
            (alt, label, number)
            for (label, alt), number in zip(targets, numbers, strict=True)
            if (alt > limit if ceiling else alt < limit)
        ]
        offenders = [(alt, label) for alt, label, _ in beyond]
        if not offenders:
            continue
        pick = max if ceiling else min
        alt, label = pick(offenders, key=lambda o: o[0])
        shown, bound = pair(alt, limit, 1)
        where = "above" if ceiling else "below"
        message = f"{label} {shown} m is {where} {name.format(bound)}"
        report.add(
            rule,
            message + others(len(offenders), f"waypoints are {where} it"),
            limit,
            alt,
            [number for _, _, number in beyond],
        )


def check_distance(
    rails: SafetyRails,
    label: str,
    distance: float,
    suffix: str,
    report: Report,
    items: Sequence[int | None] = (),
) -> None:
    """A place ``distance`` metres from home against the range limit."""
    limit = rails.max_distance_from_home_m
    if limit is not None and distance > limit:
        shown, bound = pair(distance, limit, 0)
        report.add(
            MAX_DISTANCE_FROM_HOME,
            f"{label} is {shown} m from home; the limit is {bound} m{suffix}",
            limit,
            distance,
            items,
        )
