"""The battery a mission needs: flown from where the vehicle is, home again, and landed."""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from dataclasses import dataclass, fields

from backend.safety.limits import require_target
from backend.safety.mission_waypoints import Waypoint
from backend.safety.snapshot import VehicleSnapshot, altitude, home, known, position
from backend.safety.violations import and_join
from common.geodesy import haversine_m


@dataclass(frozen=True)
class BatteryModel:
    capacity_mah: float = 5000
    hover_current_a: float = 15.0
    cruise_speed_m_s: float = 5.0
    climb_rate_m_s: float = 2.5
    descent_rate_m_s: float = 1.5

    def __post_init__(self) -> None:
        for f in fields(self):
            value = getattr(self, f.name)
            if not (math.isfinite(value) and value > 0):
                raise ValueError(f"{f.name} {value} must be a finite number > 0")


# A small multirotor's, until a vehicle's own is known.
DEFAULT_BATTERY_MODEL = BatteryModel()


@dataclass(frozen=True)
class BatteryEstimate:
    """distance_m is horizontal, including the return home; percentages are of capacity."""

    distance_m: float
    flight_time_s: float
    required_pct: float
    available_pct: float | None


def missing_for_estimate(vehicle: VehicleSnapshot) -> list[str]:
    """What the estimate needs to know of the vehicle and does not."""
    missing = []
    if position(vehicle) is None:
        missing.append("position")
    if home(vehicle) is None:
        missing.append("home position")
    if altitude(vehicle) is None:
        missing.append("altitude")
    return missing


def estimate_plan(
    vehicle: VehicleSnapshot,
    waypoints: Sequence[Waypoint],
    model: BatteryModel = DEFAULT_BATTERY_MODEL,
) -> BatteryEstimate:
    """Battery needed to fly the waypoints from where the vehicle is, return home and land.

    Conservative multirotor model: horizontal and vertical moves are flown one after the
    other, and the whole flight draws hover current. Raises ValueError when the vehicle's
    position, home or altitude is not known.
    """
    missing = missing_for_estimate(vehicle)
    here, start, alt = position(vehicle), home(vehicle), altitude(vehicle)
    if missing or here is None or start is None or alt is None:
        raise ValueError(
            f"cannot estimate the mission: the vehicle's {and_join(missing)} not known"
        )
    for i, wp in enumerate(waypoints, start=1):
        require_target(f"waypoint {i}", wp.lat, wp.lon, wp.alt_rel)
    stops = [(here.lat, here.lon, alt)]
    stops += [(wp.lat, wp.lon, wp.alt_rel) for wp in waypoints]
    last_alt = stops[-1][2]
    stops += [(start.lat, start.lon, last_alt), (start.lat, start.lon, 0.0)]  # return, land
    distance = time = 0.0
    for (lat1, lon1, alt1), (lat2, lon2, alt2) in itertools.pairwise(stops):
        leg = haversine_m(lat1, lon1, lat2, lon2)
        climb = alt2 - alt1
        distance += leg
        time += leg / model.cruise_speed_m_s
        time += climb / model.climb_rate_m_s if climb > 0 else -climb / model.descent_rate_m_s
    # Charge in mAh is amps * seconds / 3.6.
    required = time * model.hover_current_a / 3.6 / model.capacity_mah * 100
    return BatteryEstimate(distance, time, required, known(vehicle.battery_remaining_pct))
