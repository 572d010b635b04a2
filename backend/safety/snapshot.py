"""What the rails know of a vehicle: the hub's last report of it, read so that anything
not known (None, NaN, or an autopilot's 0°N 0°E "no position yet") stays unknown and the
rules that need it fail closed."""

from __future__ import annotations

import math
from dataclasses import dataclass

from common.geodesy import GeoPoint


@dataclass(frozen=True)
class VehicleSnapshot:
    """What the hub last heard from a vehicle; None (or NaN) means not known."""

    lat: float | None
    lon: float | None
    alt_rel: float | None
    home_lat: float | None
    home_lon: float | None
    battery_remaining_pct: float | None
    armed: bool
    landed: bool
    home_alt_msl: float | None = None


def known(value: float | None) -> float | None:
    return value if value is not None and math.isfinite(value) else None


def _point(lat: float | None, lon: float | None) -> GeoPoint | None:
    lat, lon = known(lat), known(lon)
    if lat is None or lon is None or (lat, lon) == (0.0, 0.0):
        # 0°N 0°E is an autopilot's "no position yet" (ArduPilot before its EKF origin),
        # from an agent that passed it on: unknown, so the rules fail closed.
        return None
    return GeoPoint(lat, lon)


def position(vehicle: VehicleSnapshot) -> GeoPoint | None:
    return _point(vehicle.lat, vehicle.lon)


def home(vehicle: VehicleSnapshot) -> GeoPoint | None:
    return _point(vehicle.home_lat, vehicle.home_lon)


def altitude(vehicle: VehicleSnapshot) -> float | None:
    alt = known(vehicle.alt_rel)
    # A landed vehicle is on the ground; its altitude reading only adds barometer drift.
    return 0.0 if alt is None and vehicle.landed else alt
