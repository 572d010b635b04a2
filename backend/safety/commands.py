"""The command rails: arm, take-off, go-to and a new home, each checked against the rails
before it is sent. Altitudes are metres above home.

Landing, RTL, hold, mode changes and disarming have no rails here: they are how an
operator gets out of trouble.
"""

from __future__ import annotations

from typing import Final

from backend.safety.geofence import check_inside, check_way_to
from backend.safety.limits import (
    check_altitudes,
    check_distance,
    check_launch_battery,
    require_altitude,
    require_target,
)
from backend.safety.rails import SafetyRails
from backend.safety.snapshot import VehicleSnapshot, home, known, position
from backend.safety.violations import HOME_ALTITUDE, MAX_DISTANCE_FROM_HOME, Report, Violation
from common.geodesy import GeoPoint, haversine_m

# Every altitude a vehicle is given is measured from home's: moving home up or down
# moves them all, ceilings included. A new home may differ from the old by this much.
HOME_ALTITUDE_TOLERANCE_M: Final = 10.0


def check_arm(rails: SafetyRails, vehicle: VehicleSnapshot) -> list[Violation]:
    report = Report()
    check_launch_battery(rails, vehicle, report)
    return report.violations()


def check_takeoff(
    rails: SafetyRails, vehicle: VehicleSnapshot, altitude_m: float
) -> list[Violation]:
    require_altitude("take-off", altitude_m)
    report = Report()
    check_launch_battery(rails, vehicle, report)
    check_altitudes(rails, [("take-off altitude", altitude_m)], report)
    if rails.geofence is not None:
        check_inside(rails.geofence, position(vehicle), "vehicle", report)
    return report.violations()


def check_goto(
    rails: SafetyRails, vehicle: VehicleSnapshot, lat: float, lon: float, altitude_m: float
) -> list[Violation]:
    require_target("target", lat, lon, altitude_m)
    report = Report()
    check_altitudes(rails, [("target altitude", altitude_m)], report)
    if rails.geofence is not None:
        check_way_to(
            rails.geofence,
            position(vehicle),
            GeoPoint(lat, lon),
            report,
            label="target",
            leg_label="the target",
        )
    if rails.max_distance_from_home_m is not None:
        start = home(vehicle)
        if start is None:
            report.unknown("home position", MAX_DISTANCE_FROM_HOME)
        else:
            distance = haversine_m(start.lat, start.lon, lat, lon)
            check_distance(rails, "target", distance, "", report)
    return report.violations()


def check_set_home(
    rails: SafetyRails,
    vehicle: VehicleSnapshot,
    lat: float | None,
    lon: float | None,
    alt_msl: float | None = None,
) -> list[Violation]:
    """A new home at (lat, lon, alt_msl), or where the vehicle is when those are None.

    Home is where RTL, and every failsafe that returns, flies to: a home outside the
    geofence, or one reached by a straight leg that leaves it, would send the vehicle out
    of the fence; and the range limit is measured from home, so home may not move further
    than that limit from where it is now. Every altitude is measured from home's, so its
    altitude may barely change, and home is not taken from a vehicle in the air.
    """
    report = Report()
    if lat is None and not vehicle.landed:
        report.add(
            HOME_ALTITUDE,
            "the vehicle is in the air: home would take its altitude, and every altitude "
            "measured from home (take-off, go-to, RTL, the ceiling) would move with it",
            None,
            None,
        )
    if alt_msl is not None:
        old_alt = known(vehicle.home_alt_msl)
        if old_alt is None:
            report.unknown("home altitude", HOME_ALTITUDE)
        elif abs(alt_msl - old_alt) > HOME_ALTITUDE_TOLERANCE_M:
            report.add(
                HOME_ALTITUDE,
                f"new home is {alt_msl - old_alt:+.1f} m from the current home's altitude "
                f"(at most ±{HOME_ALTITUDE_TOLERANCE_M:g} m): every altitude measured from "
                "home would move with it",
                HOME_ALTITUDE_TOLERANCE_M,
                alt_msl - old_alt,
            )
    here = position(vehicle)
    if lat is None or lon is None:
        label, target = "the vehicle's position (the new home)", here
    else:
        require_target("home", lat, lon, 0.0)
        label, target = "new home", GeoPoint(lat, lon)
    if rails.geofence is not None:
        check_way_to(
            rails.geofence,
            here,
            target,
            report,
            label=label,
            leg_label="the new home",
            consequence="RTL would fly",
        )
    if rails.max_distance_from_home_m is not None:
        start = home(vehicle)
        if start is None or target is None:
            report.unknown("home position" if start is None else "position", MAX_DISTANCE_FROM_HOME)
        else:
            distance = haversine_m(start.lat, start.lon, target.lat, target.lon)
            check_distance(rails, label, distance, "", report)
    return report.violations()
