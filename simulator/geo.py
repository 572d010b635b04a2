"""Flat-earth conversion between local metres around home and latitude/longitude.

Uses ArduPilot's own scaling (``LOCATION_SCALING_FACTOR`` in AP_Common/Location.cpp), so
offsets match what SITL reports to within centimetres over a few kilometres.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

# Metres per 1e-7 degree of latitude, as ArduPilot defines it.
LOCATION_SCALING_FACTOR = 0.011131884502145034
METRES_PER_DEGREE = LOCATION_SCALING_FACTOR * 1e7


@dataclass(frozen=True)
class GeoPoint:
    """A WGS84 position: degrees, and metres above mean sea level."""

    lat: float
    lon: float
    alt: float

    def __post_init__(self) -> None:
        if not (-90.0 <= self.lat <= 90.0 and -180.0 <= self.lon <= 180.0):
            raise ValueError(f"latitude/longitude out of range: {self.lat}, {self.lon}")


@dataclass(frozen=True)
class LocalFrame:
    """North-east offsets around a home point; altitudes are relative to home."""

    home: GeoPoint

    @property
    def _lon_scale(self) -> float:
        return max(math.cos(math.radians(self.home.lat)), 0.01)

    def to_global(self, north: float, east: float, up: float) -> GeoPoint:
        lat = self.home.lat + north / METRES_PER_DEGREE
        lon = self.home.lon + east / (METRES_PER_DEGREE * self._lon_scale)
        lon = (lon + 180.0) % 360.0 - 180.0
        return GeoPoint(max(-90.0, min(90.0, lat)), lon, self.home.alt + up)

    def to_local(self, lat: float, lon: float) -> tuple[float, float]:
        """(north, east) metres of a latitude/longitude from home."""
        dlon = (lon - self.home.lon + 180.0) % 360.0 - 180.0
        north = (lat - self.home.lat) * METRES_PER_DEGREE
        east = dlon * METRES_PER_DEGREE * self._lon_scale
        return north, east
