"""The simulator's world: obstacles a LIDAR sees, and the geometry to ray-cast against them.

Every obstacle is a vertical prism: a footprint on the ground (a box, a cylinder, a wall, or
any simple polygon) extruded from ``z_min`` to ``z_max`` metres above the ground at the
vehicle's EKF origin. Coordinates are metres east and north of that origin (the ENU order
of common.geodesy). A ray against a vertical prism's side crosses it where the ray's
horizontal projection crosses the footprint's outline, so casting is 2-D geometry plus a
height check, exact for tilted rays too; the flat ground at z = 0 is the one horizontal
surface.

A scene file is JSON (``load_scene``)::

    {"obstacles": [
        {"kind": "box", "center": [10, 5], "size": [4, 2], "yaw_deg": 30, "height": 6},
        {"kind": "cylinder", "center": [-8, 3], "radius": 0.5, "height": 8},
        {"kind": "wall", "start": [-15, -10], "end": [15, -10], "thickness": 0.2},
        {"kind": "polygon", "points": [[0, 12], [6, 14], [3, 18]], "z_min": 0, "height": 5}
    ]}

``yaw_deg`` turns a box clockwise from north, as a heading does.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal

import numpy as np
import numpy.typing as npt

Array = npt.NDArray[np.float64]
NO_HIT = math.inf
_EPS = 1e-12


@dataclass(frozen=True)
class Polygon:
    """A closed outline (counter-clockwise or not), extruded from z_min to z_max."""

    points: tuple[tuple[float, float], ...]
    z_min: float = 0.0
    z_max: float = 6.0

    def __post_init__(self) -> None:
        if len(self.points) < 3:
            raise ValueError("a polygon needs at least 3 points")
        if not self.z_max > self.z_min:
            raise ValueError("an obstacle's top must be above its bottom")

    def segments(self) -> Array:
        """(n, 4) rows of x0, y0, x1, y1: the outline's edges."""
        pts = np.asarray(self.points, dtype=np.float64)
        return np.hstack([pts, np.roll(pts, -1, axis=0)])


@dataclass(frozen=True)
class Cylinder:
    center: tuple[float, float]
    radius: float
    z_min: float = 0.0
    z_max: float = 6.0

    def __post_init__(self) -> None:
        if self.radius <= 0.0:
            raise ValueError("a cylinder's radius must be > 0")
        if not self.z_max > self.z_min:
            raise ValueError("an obstacle's top must be above its bottom")


def box(
    center: tuple[float, float],
    size: tuple[float, float],
    yaw_deg: float = 0.0,
    z_min: float = 0.0,
    z_max: float = 6.0,
) -> Polygon:
    """A rectangle ``size`` (east, north extent before turning) about ``center``."""
    half_e, half_n = size[0] / 2.0, size[1] / 2.0
    yaw = math.radians(yaw_deg)
    cos, sin = math.cos(yaw), math.sin(yaw)
    corners = [(-half_e, -half_n), (half_e, -half_n), (half_e, half_n), (-half_e, half_n)]
    # clockwise from north: east' = e cos + n sin, north' = -e sin + n cos
    points = tuple(
        (center[0] + e * cos + n * sin, center[1] - e * sin + n * cos) for e, n in corners
    )
    return Polygon(points, z_min, z_max)


def wall(
    start: tuple[float, float],
    end: tuple[float, float],
    thickness: float = 0.2,
    z_min: float = 0.0,
    z_max: float = 6.0,
) -> Polygon:
    """A straight wall from ``start`` to ``end``, ``thickness`` across."""
    dx, dy = end[0] - start[0], end[1] - start[1]
    length = math.hypot(dx, dy)
    if length <= 0.0 or thickness <= 0.0:
        raise ValueError("a wall needs a length and a thickness")
    nx, ny = -dy / length * thickness / 2.0, dx / length * thickness / 2.0
    points = (
        (start[0] + nx, start[1] + ny),
        (end[0] + nx, end[1] + ny),
        (end[0] - nx, end[1] - ny),
        (start[0] - nx, start[1] - ny),
    )
    return Polygon(points, z_min, z_max)


Obstacle = Polygon | Cylinder


@dataclass
class World:
    """The obstacles, flattened once into arrays for casting many rays at a time."""

    obstacles: list[Obstacle] = field(default_factory=list)

    def __post_init__(self) -> None:
        polygons = [o for o in self.obstacles if isinstance(o, Polygon)]
        cylinders = [o for o in self.obstacles if isinstance(o, Cylinder)]
        rows = [p.segments() for p in polygons]
        heights = [np.tile([p.z_min, p.z_max], (len(p.points), 1)) for p in polygons]
        self._segments = np.vstack(rows) if rows else np.zeros((0, 4))
        self._segment_z = np.vstack(heights) if heights else np.zeros((0, 2))
        self._circles = np.array(
            [(c.center[0], c.center[1], c.radius, c.z_min, c.z_max) for c in cylinders],
            dtype=np.float64,
        ).reshape(-1, 5)

    def cast(self, origins: Array, directions: Array, max_range: float) -> Array:
        """Distance along each unit ray to the first surface it meets within
        ``max_range`` (inf where none). ``origins`` and ``directions`` are (n, 3)
        east/north/up rows; directions must be unit vectors."""
        n = len(origins)
        best = np.full(n, NO_HIT)
        ox, oy, oz = origins[:, 0:1], origins[:, 1:2], origins[:, 2:3]
        dx, dy, dz = directions[:, 0:1], directions[:, 1:2], directions[:, 2:3]
        if len(self._segments):
            s = self._segments
            ex, ey = (s[:, 2] - s[:, 0])[None, :], (s[:, 3] - s[:, 1])[None, :]
            wx, wy = s[:, 0][None, :] - ox, s[:, 1][None, :] - oy
            denom = dx * ey - dy * ex
            with np.errstate(divide="ignore", invalid="ignore"):
                t = (wx * ey - wy * ex) / denom  # along the ray (3-D length: d is unit)
                u = (wx * dy - wy * dx) / denom  # along the edge, 0..1
                z = oz + t * dz
            with np.errstate(invalid="ignore"):
                ok = (
                    (np.abs(denom) > _EPS)
                    & (t > 0.0)
                    & (u >= 0.0)
                    & (u <= 1.0)
                    & (z >= self._segment_z[:, 0][None, :])
                    & (z <= self._segment_z[:, 1][None, :])
                )
            best = np.minimum(best, np.where(ok, t, NO_HIT).min(axis=1))
        if len(self._circles):
            c = self._circles
            fx, fy = ox - c[:, 0][None, :], oy - c[:, 1][None, :]
            a = dx * dx + dy * dy
            b = fx * dx + fy * dy
            cc = fx * fx + fy * fy - (c[:, 2] ** 2)[None, :]
            disc = b * b - a * cc
            with np.errstate(divide="ignore", invalid="ignore"):
                root = np.sqrt(np.maximum(disc, 0.0))
                near, far = (-b - root) / a, (-b + root) / a
                t = np.where(near > 0.0, near, far)  # from inside, the far wall
                z = oz + t * dz
            with np.errstate(invalid="ignore"):
                ok = (
                    (disc >= 0.0)
                    & (a > _EPS)
                    & (t > 0.0)
                    & (z >= c[:, 3][None, :])
                    & (z <= c[:, 4][None, :])
                )
            best = np.minimum(best, np.where(ok, t, NO_HIT).min(axis=1))
        # The flat ground at z = 0, for beams tilted down.
        with np.errstate(divide="ignore", invalid="ignore"):
            t_ground = np.where(dz[:, 0] < -_EPS, -oz[:, 0] / dz[:, 0], NO_HIT)
        best = np.minimum(best, np.where(t_ground > 0.0, t_ground, NO_HIT))
        return np.where(best <= max_range, best, NO_HIT)

    def distance_to_surface(self, points: Array) -> Array:
        """Horizontal distance from each (east, north[, up]) point to the nearest obstacle
        outline: how far a LIDAR return lies from the surface it should be on."""
        px, py = points[:, 0:1], points[:, 1:2]
        best = np.full(len(points), NO_HIT)
        if len(self._segments):
            s = self._segments
            ax, ay = s[:, 0][None, :], s[:, 1][None, :]
            ex, ey = (s[:, 2] - s[:, 0])[None, :], (s[:, 3] - s[:, 1])[None, :]
            length2 = np.maximum(ex * ex + ey * ey, _EPS)
            u = np.clip(((px - ax) * ex + (py - ay) * ey) / length2, 0.0, 1.0)
            d = np.hypot(px - (ax + u * ex), py - (ay + u * ey))
            best = np.minimum(best, d.min(axis=1))
        if len(self._circles):
            c = self._circles
            d = np.abs(np.hypot(px - c[:, 0][None, :], py - c[:, 1][None, :]) - c[:, 2][None, :])
            best = np.minimum(best, d.min(axis=1))
        return best


def default_scene() -> World:
    """A small yard around the demo's home: a building, a shed, two masts, a fence, and
    an odd-shaped hangar, all within the T-mini Pro's 12 m of the take-off point."""
    return World(
        [
            box((9.0, 2.0), (4.0, 6.0), yaw_deg=15.0, z_max=8.0),
            box((-6.0, 8.0), (3.0, 2.0), z_max=3.0),
            Cylinder((-4.0, -5.0), 0.4, z_max=10.0),
            Cylinder((3.0, -7.0), 0.6, z_max=10.0),
            wall((-10.0, -10.0), (10.0, -10.0), thickness=0.2, z_max=4.0),
            Polygon(((-11.0, -2.0), (-8.0, -3.0), (-7.5, 2.0), (-10.0, 3.5)), z_max=7.0),
        ]
    )


def _pair(value: Any, name: str) -> tuple[float, float]:
    if not (isinstance(value, list | tuple) and len(value) == 2):
        raise ValueError(f"{name} must be [east, north] in metres")
    return float(value[0]), float(value[1])


def obstacle_from_dict(item: dict[str, Any]) -> Obstacle:
    """One obstacle from its scene-file form; ValueError names what is wrong."""
    kind: Literal["box", "cylinder", "wall", "polygon"] | Any = item.get("kind")
    z_min = float(item.get("z_min", 0.0))
    z_max = z_min + float(item.get("height", 6.0))
    if kind == "box":
        size = _pair(item.get("size"), "box size")
        return box(
            _pair(item.get("center"), "box center"),
            size,
            float(item.get("yaw_deg", 0.0)),
            z_min,
            z_max,
        )
    if kind == "cylinder":
        center = _pair(item.get("center"), "cylinder center")
        return Cylinder(center, float(item.get("radius", 0.0)), z_min, z_max)
    if kind == "wall":
        start, end = _pair(item.get("start"), "wall start"), _pair(item.get("end"), "wall end")
        return wall(start, end, float(item.get("thickness", 0.2)), z_min, z_max)
    if kind == "polygon":
        raw = item.get("points")
        if not isinstance(raw, list):
            raise ValueError("polygon points must be a list of [east, north]")
        return Polygon(tuple(_pair(p, "polygon point") for p in raw), z_min, z_max)
    raise ValueError(f"unknown obstacle kind {kind!r}: box, cylinder, wall or polygon")


def load_scene(path: Path) -> World:
    """A world from a scene file (see the module's docstring)."""
    data = json.loads(path.read_text())
    if not isinstance(data, dict) or not isinstance(data.get("obstacles"), list):
        raise ValueError(f"{path}: expected an object with an 'obstacles' list")
    obstacles = []
    for number, item in enumerate(data["obstacles"]):
        if not isinstance(item, dict):
            raise ValueError(f"{path}: obstacle {number} is not an object")
        try:
            obstacles.append(obstacle_from_dict(item))
        except (TypeError, ValueError) as error:
            raise ValueError(f"{path}: obstacle {number}: {error}") from None
    return World(obstacles)
