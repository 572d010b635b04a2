"""Geodesy for the whole fleet: WGS84 positions, local east-north-up frames and distances.

One module, shared by the agent, the hub and the simulator, so that every part converts
between latitude/longitude and local metres the same way and in the same order: positions
go in as (lat, lon[, alt]) and local offsets come out, and go back in, as (east, north[, up]).

The formulas are pymap3d's (geodetic <-> ECEF <-> ENU on the WGS84 ellipsoid, and Meeus's
haversine). pymap3d is pure Python with no dependencies, so it fits the agent's base install
on a Pi Zero; pyproj would give the same numbers (tests/unit/common/test_geodesy.py checks against
it) from a large binary wheel. Without numpy, pymap3d works on floats with the math module,
which is what keeps these calls to microseconds (bench/bench_geodesy.py).
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass
from typing import Final, NamedTuple

from pymap3d.ellipsoid import Ellipsoid
from pymap3d.enu import enu2geodetic, geodetic2enu
from pymap3d.haversine import anglesep_meeus

WGS84: Final = Ellipsoid.from_name("wgs84")
WGS84_A_M: Final[float] = WGS84.semimajor_axis
WGS84_F: Final[float] = WGS84.flattening
# IUGG mean radius: the sphere that best fits the ellipsoid, for haversine distances.
EARTH_MEAN_RADIUS_M: Final = 6_371_008.8


@dataclass(frozen=True, slots=True)
class GeoPoint:
    """A WGS84 position in degrees, and an altitude in metres.

    The altitude's datum (mean sea level or the ellipsoid) is the caller's: a LocalFrame
    only ever takes differences of heights a few kilometres apart, over which the two
    datums differ by centimetres.
    """

    lat: float
    lon: float
    alt: float = 0.0


class Enu(NamedTuple):
    """Metres east, north and up of a frame's origin."""

    east: float
    north: float
    up: float


class LocalFrame:
    """East-north-up metres on the plane tangent to the WGS84 ellipsoid at an origin.

    Two ways in and out:
    - `to_enu` / `from_enu`: true 3-D east-north-up (a 3-D view, a camera footprint).
    - `to_local` / `to_geo`: a point on the surface through the origin (at the origin's
      height) and its east/north on the tangent plane, up left out. This is the map a
      geofence or a flight controller works on: a vehicle holding its altitude above home
      keeps it however far it flies, rather than rising off the tangent plane.

    The plane's east/north are exact projections (no scaling of degrees by cos(latitude)),
    so there is no special case at the antimeridian; the plane bends away from the surface
    by distance cubed over 6R² (4 mm at 10 km, 4 m at 100 km), and only the near side of
    the Earth maps one-to-one: keep to a few hundred kilometres of the origin.
    """

    __slots__ = ("origin",)

    def __init__(self, lat: float, lon: float, alt: float = 0.0) -> None:
        self.origin = GeoPoint(lat, lon, alt)

    def to_enu(self, lat: float, lon: float, alt: float) -> Enu:
        o = self.origin
        east, north, up = geodetic2enu(lat, lon, alt, o.lat, o.lon, o.alt, WGS84)
        return Enu(east, north, up)

    def from_enu(self, east: float, north: float, up: float) -> GeoPoint:
        o = self.origin
        lat, lon, alt = enu2geodetic(east, north, up, o.lat, o.lon, o.alt, WGS84)
        return GeoPoint(lat, lon, alt)

    def to_local(self, lat: float, lon: float) -> tuple[float, float]:
        """(east, north) metres of a latitude/longitude, taken at the origin's height."""
        east, north, _ = self.to_enu(lat, lon, self.origin.alt)
        return east, north

    def to_geo(self, east: float, north: float) -> tuple[float, float]:
        """(lat, lon) of the point at the origin's height whose east/north are these:
        the inverse of `to_local`."""
        # Drop from the tangent plane along the vertical onto the surface. Start from the
        # sphere's drop, distance² / 2R, which leaves a fraction of a percent of it; a height
        # still wrong by h moves the point sideways by about h * distance / R, so one call
        # suffices within a few kilometres and a second reaches micrometres at 100 km.
        distance = math.hypot(east, north)
        up = -(distance**2) / (2 * EARTH_MEAN_RADIUS_M)
        for _ in range(4):
            point = self.from_enu(east, north, up)
            height = point.alt - self.origin.alt
            if abs(height) * distance <= 1e-9 * EARTH_MEAN_RADIUS_M:
                break
            up -= height
        return point.lat, point.lon


def haversine_m(lat1: float, lon1: float, lat2: float, lon2: float) -> float:
    """Great-circle distance in metres on the mean-radius sphere (within 0.6% of the
    ellipsoidal distance, which is ample for range limits and battery estimates)."""
    # pymap3d takes longitude first.
    angle = anglesep_meeus(
        math.radians(lon1), math.radians(lat1), math.radians(lon2), math.radians(lat2), deg=False
    )
    return EARTH_MEAN_RADIUS_M * float(angle)


def centre_of(points: Iterable[tuple[float, float]]) -> tuple[float, float]:
    """(lat, lon) of the mean direction of ``points`` (given as (lat, lon)): a centre for a
    tangent plane that does not care where longitude wraps (a mean of degrees would put the
    centre of 179 and -179 at 0).

    The mean of unit vectors on the sphere, not of pymap3d's ECEF positions: on shapes up to
    a few hundred kilometres across the two differ by metres, which a tangent plane's origin
    does not notice, and this is 25 times faster on a 1,000-vertex geofence."""
    sx = sy = sz = 0.0
    for lat, lon in points:
        phi, lam = math.radians(lat), math.radians(lon)
        sx += math.cos(phi) * math.cos(lam)
        sy += math.cos(phi) * math.sin(lam)
        sz += math.sin(phi)
    return math.degrees(math.atan2(sz, math.hypot(sx, sy))), math.degrees(math.atan2(sy, sx))
