"""The 3D view's local frame: metres east, north and up of one origin (common.geodesy).

viser sends point clouds as float16 and the browser draws in float32, so the scene works
in local metres: geodetic coordinates would lose all precision. The origin is configured
(GCS_VIZ_ORIGIN) or the first home position the fleet reports.
"""

from __future__ import annotations

import math
from collections import Counter
from collections.abc import Callable

import numpy as np
import numpy.typing as npt
from pymap3d.ecef import geodetic2ecef

from common.geodesy import WGS84, GeoPoint, LocalFrame
from protocol.messages import VehicleState

# Farther than this from the origin is not a fleet we can draw truthfully (the tangent
# plane bends away; common.geodesy), and far more likely a bad fix.
MAX_RANGE_M = 200_000.0
MIN_ALT_M = -1_000.0
MAX_ALT_M = 20_000.0

Vector = npt.NDArray[np.float64]
# A vehicle's home altitude (metres above sea level), None while unknown: surveys and
# formations give heights above each vehicle's home.
HomeAltitude = Callable[[str], float | None]


def parse_origin(text: str | None) -> GeoPoint | None:
    """``lat,lon[,alt_msl]`` (GCS_VIZ_ORIGIN), checked like a position."""
    if not text:
        return None
    values = [float(part) for part in text.split(",")]
    lat, lon = values[0], values[1]
    alt = values[2] if len(values) > 2 else math.nan
    if not (-90 <= lat <= 90 and -180 <= lon <= 180):
        raise ValueError(f"GCS_VIZ_ORIGIN {text!r}: latitude or longitude out of range")
    return GeoPoint(lat, lon, alt)


class SceneFrame:
    """Places positions in the local frame, and counts those it will not place."""

    def __init__(self, origin: GeoPoint | None = None) -> None:
        self.configured = origin
        self.local: LocalFrame | None = None
        if origin is not None and math.isfinite(origin.alt):
            self.local = LocalFrame(origin.lat, origin.lon, origin.alt)
        # Reason -> how many positions were skipped for it (shown in the panel).
        self.skipped: Counter[str] = Counter()

    def anchor(self, state: VehicleState) -> bool:
        """Fix the origin from the first usable home (or the configured origin, given its
        altitude from that home); True once the frame is anchored."""
        if self.local is not None:
            return True
        home = (state.home_lat, state.home_lon, state.home_alt_msl)
        if not all(value is not None and math.isfinite(value) for value in home):
            return False
        lat, lon, alt = (float(value) for value in home)  # type: ignore[arg-type]
        if not (-90 <= lat <= 90 and -180 <= lon <= 180):
            return False
        if self.configured is not None:
            lat, lon = self.configured.lat, self.configured.lon
        self.local = LocalFrame(lat, lon, alt)
        return True

    def vehicle(self, state: VehicleState) -> Vector | None:
        """Where the vehicle is, or None (no fix yet, or a position that is skipped and
        counted): a vehicle without a position is never drawn at the origin."""
        if state.lat is None or state.lon is None:
            return None  # no position yet: not a fault, nothing to draw
        alt = state.alt_msl
        if alt is None and state.alt_rel is not None and state.home_alt_msl is not None:
            alt = state.home_alt_msl + state.alt_rel
        if alt is None:
            self.skipped["no altitude"] += 1
            return None
        return self.place(state.lat, state.lon, alt)

    def home(self, state: VehicleState) -> Vector | None:
        if state.home_lat is None or state.home_lon is None or state.home_alt_msl is None:
            return None
        return self.place(state.home_lat, state.home_lon, state.home_alt_msl)

    def ground(self, home_alt_msl: float | None) -> float | None:
        """The height a vehicle's "above home" counts from: its home's, or while that is
        unknown the origin's (the first home the fleet reported); None without an origin."""
        if home_alt_msl is not None and math.isfinite(home_alt_msl):
            return home_alt_msl
        return None if self.local is None else self.local.origin.alt

    def place(self, lat: float, lon: float, alt: float) -> Vector | None:
        if not all(math.isfinite(value) for value in (lat, lon, alt)):
            self.skipped["not a number"] += 1
            return None
        if not (-90 <= lat <= 90 and -180 <= lon <= 180 and MIN_ALT_M <= alt <= MAX_ALT_M):
            self.skipped["out of range"] += 1
            return None
        if self.local is None:
            self.skipped["no origin yet"] += 1
            return None
        east, north, up = self.local.to_enu(lat, lon, alt)
        if math.hypot(east, north) > MAX_RANGE_M:
            self.skipped["too far from the origin"] += 1
            return None
        return np.array([east, north, up], dtype=np.float64)


def attitude_wxyz(
    roll_deg: float | None, pitch_deg: float | None, heading_deg: float | None
) -> Vector:
    """The body's orientation in east-north-up as a quaternion (w, x, y, z).

    MAVLink's attitude is of the body's forward-right-down axes in north-east-down: roll
    right-wing-down, pitch nose-up, heading clockwise from north. In east-north-up with
    a forward-left-up body that is yaw = 90° - heading about up, pitch negated about the
    body's left axis, roll unchanged about forward: R = Rz(yaw) Ry(-pitch) Rx(roll).
    Missing angles count as level, facing north.
    """
    roll = math.radians(roll_deg or 0.0)
    pitch = -math.radians(pitch_deg or 0.0)
    yaw = math.radians(90.0 - (heading_deg if heading_deg is not None else 0.0))
    cr, sr = math.cos(roll / 2), math.sin(roll / 2)
    cp, sp = math.cos(pitch / 2), math.sin(pitch / 2)
    cy, sy = math.cos(yaw / 2), math.sin(yaw / 2)
    return np.array(
        [
            cr * cp * cy + sr * sp * sy,
            sr * cp * cy - cr * sp * sy,
            cr * sp * cy + sr * cp * sy,
            cr * cp * sy - sr * sp * cy,
        ]
    )


def _enu_axes(origin: GeoPoint) -> Vector:
    """(3, 3) rows: the origin's east, north and up unit vectors in ECEF."""
    lat, lon = math.radians(origin.lat), math.radians(origin.lon)
    return np.array(
        [
            [-math.sin(lon), math.cos(lon), 0.0],
            [-math.sin(lat) * math.cos(lon), -math.sin(lat) * math.sin(lon), math.cos(lat)],
            [math.cos(lat) * math.cos(lon), math.cos(lat) * math.sin(lon), math.sin(lat)],
        ]
    )


def reframe(points: npt.NDArray[np.floating], source: LocalFrame, target: LocalFrame) -> Vector:
    """(n, 3) east-north-up points of one local frame, in another: the scans' site frame
    may have another origin than the scene's. Both are rotations of ECEF about their
    origins, so this is one exact rigid transform (no per-point geodesy): a scan's 720
    points cost microseconds."""
    points = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    if source.origin == target.origin or not len(points):
        return points
    s, t = source.origin, target.origin
    source_axes, target_axes = _enu_axes(s), _enu_axes(t)
    offset = np.array(geodetic2ecef(s.lat, s.lon, s.alt, WGS84)) - np.array(
        geodetic2ecef(t.lat, t.lon, t.alt, WGS84)
    )
    ecef = points @ source_axes + offset  # relative to the target's origin
    moved: Vector = ecef @ target_axes.T
    return moved
