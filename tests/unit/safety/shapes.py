"""Shared shapes for the safety tests, drawn in metres on a local plane so the numbers in
assertions are easy to check by hand."""

from __future__ import annotations

import math

from backend.safety import Geofence, GeoPoint, VehicleSnapshot, Violation, Waypoint
from common.geodesy import EARTH_MEAN_RADIUS_M, LocalFrame

ORIGIN = (47.0, 8.0)
FRAME = LocalFrame(*ORIGIN)

# A U open to the north: a 100 m wide, 200 m deep notch between two arms.
#   (0,300) ┌──┐(100,300)  (200,300)┌──┐(300,300)
#           │  │                   │  │
#           │  └───────────────────┘  │   notch floor at y=100
#   (0,0)   └─────────────────────────┘(300,0)
U_SHAPE: list[tuple[float, float]] = [
    (0, 0),
    (300, 0),
    (300, 300),
    (200, 300),
    (200, 100),
    (100, 100),
    (100, 300),
    (0, 300),
]


def geo(east: float, north: float) -> GeoPoint:
    return GeoPoint(*FRAME.to_geo(east, north))


def wp(east: float, north: float, alt: float) -> Waypoint:
    p = geo(east, north)
    return Waypoint(p.lat, p.lon, alt)


def u_fence(max_altitude_m: float | None = None) -> Geofence:
    return Geofence(tuple(geo(e, n) for e, n in U_SHAPE), max_altitude_m=max_altitude_m)


def north_of(point: GeoPoint, metres: float) -> GeoPoint:
    """Exactly `metres` by haversine: moves along the meridian on the mean sphere."""
    return GeoPoint(point.lat + math.degrees(metres / EARTH_MEAN_RADIUS_M), point.lon)


def vehicle(
    at: GeoPoint | None = None,
    home: GeoPoint | None = None,
    *,
    alt: float | None = 0.0,
    battery: float | None = 90.0,
    landed: bool = True,
) -> VehicleSnapshot:
    """A vehicle at `at` (default: inside the U's west arm) with home where it stands."""
    here = at if at is not None else geo(50, 50)
    base = home if home is not None else here
    return VehicleSnapshot(
        lat=here.lat,
        lon=here.lon,
        alt_rel=alt,
        home_lat=base.lat,
        home_lon=base.lon,
        battery_remaining_pct=battery,
        armed=not landed,
        landed=landed,
    )


UNKNOWN = VehicleSnapshot(
    lat=None,
    lon=None,
    alt_rel=None,
    home_lat=None,
    home_lon=None,
    battery_remaining_pct=None,
    armed=False,
    landed=True,
)


def rules(violations: list[Violation]) -> list[str]:
    return [v.rule for v in violations]


def only(violations: list[Violation], rule: str) -> Violation:
    matching = [v for v in violations if v.rule == rule]
    assert len(matching) == 1, violations
    return matching[0]
