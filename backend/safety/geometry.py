"""Geometry for the safety rails: polygon tests on a local plane (common/geodesy.py's
LocalFrame, tangent to the Earth), computed by shapely (GEOS) in metres on that plane.

Geofences are small (at most MAX_POLYGON_RADIUS_M from their centre), so every polygon test
runs on a plane tangent to the Earth at the polygon's centre, in metres. On that plane a
polygon edge and a vehicle's straight leg are straight lines, which is how autopilots fly
between waypoints over these distances.

Numbers in error messages (edges, vertices) count from 1, as a person reading a list would.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Final

import numpy as np
import shapely
from shapely.geometry import LineString, Point, Polygon

from common.geodesy import LocalFrame, centre_of, haversine_m

XY = tuple[float, float]
LatLon = tuple[float, float]

MAX_POLYGON_VERTICES: Final = 1000
# Beyond this the tangent plane bends a polygon's edges by metres away from the geodesics
# they stand for; no drone-fleet geofence needs a span of more than 200 km.
MAX_POLYGON_RADIUS_M: Final = 100_000.0
MIN_POLYGON_AREA_M2: Final = 1.0
# Points closer than this to an edge count as on it. Coordinates are metres on the plane, so
# this is far above floating-point noise (about 1e-11 m at 100 km) and far below anything a
# GNSS receiver can tell apart.
TOLERANCE_M: Final = 1e-6


class InvalidGeofence(ValueError):
    """A polygon that cannot serve as a geofence; the message says what is wrong with it."""

    def __init__(self, message: str) -> None:
        super().__init__(message)
        self.message = message


# --- Plane geometry (shapely, in metres on the plane) ----------------------------------------


def _segment(a: XY, b: XY) -> LineString:
    return LineString([a, b])


def _side(a: XY, b: XY, p: XY) -> int:
    """Which side of the line a→b the point p is on: 1 left, -1 right, 0 on it."""
    dx, dy = b[0] - a[0], b[1] - a[1]
    cross = dx * (p[1] - a[1]) - dy * (p[0] - a[0])
    if abs(cross) <= TOLERANCE_M * math.hypot(dx, dy):
        return 0
    return 1 if cross > 0 else -1


def segment_relation(p1: XY, p2: XY, q1: XY, q2: XY) -> str | None:
    """How two segments meet: "cross" (interiors cross), "overlap" (collinear with a shared
    stretch), "touch" (an end lies on the other segment) or None (apart)."""
    p, q = _segment(p1, p2), _segment(q1, q2)
    if not shapely.dwithin(p, q, TOLERANCE_M):
        return None
    if p.intersection(q).length > TOLERANCE_M:
        return "overlap"
    ends = [(Point(p1), q), (Point(p2), q), (Point(q1), p), (Point(q2), p)]
    return (
        "touch" if any(shapely.dwithin(end, other, TOLERANCE_M) for end, other in ends) else "cross"
    )


def _edges(ring: Sequence[XY]) -> list[tuple[XY, XY]]:
    return [(ring[i], ring[(i + 1) % len(ring)]) for i in range(len(ring))]


class PlanarPolygon:
    """A polygon on the plane, prepared (indexed by shapely) for repeated tests.

    Points within TOLERANCE_M of the polygon count as in it, so it is tested as the
    polygon grown by that much: a fence line drawn through a waypoint, or a leg flown
    along an edge, is within the fence.
    """

    __slots__ = ("_boundary", "_covered", "ring")

    def __init__(self, ring: Sequence[XY]) -> None:
        self.ring = tuple(ring)
        polygon = Polygon(self.ring)
        self._boundary = polygon.exterior
        # Mitred, so that the corners stay corners (at most 5 tolerances out at a spike).
        self._covered = polygon.buffer(TOLERANCE_M, join_style="mitre")
        shapely.prepare(self._covered)

    def distance_to_boundary(self, p: XY) -> float:
        return float(self._boundary.distance(Point(p)))

    def contains(self, p: XY) -> bool:
        """Points on the boundary (within TOLERANCE_M) count as inside."""
        return bool(shapely.intersects_xy(self._covered, p[0], p[1]))

    def segment_leaves(self, a: XY, b: XY) -> bool:
        """True when any part of the straight segment a→b lies outside the polygon. Both
        ends inside is not enough for a concave polygon: the segment can cut across a
        notch."""
        if not (self.contains(a) and self.contains(b)):
            return True
        if math.dist(a, b) <= TOLERANCE_M:
            return False
        return not self._covered.covers(_segment(a, b))


def distance_to_boundary(p: XY, ring: Sequence[XY]) -> float:
    return PlanarPolygon(ring).distance_to_boundary(p)


def point_in_polygon(p: XY, ring: Sequence[XY]) -> bool:
    """See PlanarPolygon.contains; build a PlanarPolygon once for repeated tests."""
    return PlanarPolygon(ring).contains(p)


def segment_leaves_polygon(a: XY, b: XY, ring: Sequence[XY]) -> bool:
    """See PlanarPolygon.segment_leaves; build a PlanarPolygon once for repeated tests."""
    return PlanarPolygon(ring).segment_leaves(a, b)


# --- Polygon validation ---------------------------------------------------------------------


def _check_coordinates(vertices: Sequence[LatLon]) -> None:
    for i, (lat, lon) in enumerate(vertices, start=1):
        if not (math.isfinite(lat) and math.isfinite(lon)):
            raise InvalidGeofence(f"vertex {i} ({lat}, {lon}) is not a finite number")
        if not -90.0 <= lat <= 90.0:
            raise InvalidGeofence(f"vertex {i} latitude {lat} is outside -90..90")
        if not -180.0 <= lon <= 180.0:
            raise InvalidGeofence(f"vertex {i} longitude {lon} is outside -180..180")


def _check_simple(ring: Sequence[XY]) -> None:
    """No two edges may meet except neighbours at their shared vertex. Only the pairs of
    edges an R-tree finds within TOLERANCE_M of each other are compared."""
    n = len(ring)
    for i in range(n):
        _check_neighbours(ring, i, (i + 1) % n)
    edges = _edges(ring)
    segments = shapely.linestrings(np.asarray(edges, dtype=float))  # one per edge, at once
    assert isinstance(segments, np.ndarray)  # an array for an array of edges
    tree = shapely.STRtree(segments)
    near = tree.query(tree.geometries, predicate="dwithin", distance=TOLERANCE_M)
    pairs = sorted({(min(i, j), max(i, j)) for i, j in near.T.tolist() if i != j})
    for first, second in pairs:
        if (second - first) in (1, n - 1):
            continue  # neighbours, checked above
        relation = segment_relation(*edges[first], *edges[second])
        if relation is not None:
            raise InvalidGeofence(f"edges {first + 1} and {second + 1} {relation}")


def _check_neighbours(ring: Sequence[XY], first: int, second: int) -> None:
    """Edge `first` runs into edge `second` at their shared vertex. Neighbours always meet
    there; they are only wrong if the second doubles back along the first, leaving a spike
    with no area."""
    before, shared, after = ring[first], ring[second], ring[(second + 1) % len(ring)]
    if _side(before, shared, after) != 0:
        return
    back = (shared[0] - before[0]) * (after[0] - shared[0]) + (shared[1] - before[1]) * (
        after[1] - shared[1]
    )
    if back < 0:
        low, high = sorted((first + 1, second + 1))
        raise InvalidGeofence(f"edges {low} and {high} fold back on each other")


def _collinear(ring: Sequence[XY], tolerance_m: float = 0.01) -> bool:
    a = ring[0]
    b = max(ring, key=lambda p: math.hypot(p[0] - a[0], p[1] - a[1]))
    length = math.hypot(b[0] - a[0], b[1] - a[1])
    return all(
        abs((b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0])) <= tolerance_m * length
        for p in ring
    )


class FencePolygon:
    """A validated polygon, projected once onto its own local plane for repeated tests.

    Raises InvalidGeofence naming the first problem found. A repeated closing vertex (as in
    GeoJSON rings) is dropped; any other vertex repeated in a row is an error, so that edge
    numbers in messages match what the user drew.
    """

    __slots__ = ("_plane", "frame", "radius_m", "vertices")

    def __init__(self, vertices: Sequence[LatLon]) -> None:
        points = [(float(lat), float(lon)) for lat, lon in vertices]
        if len(points) > 1 and points[0] == points[-1]:
            points.pop()
        if len(points) > MAX_POLYGON_VERTICES:
            raise InvalidGeofence(
                f"{len(points)} vertices; a geofence may have at most {MAX_POLYGON_VERTICES}"
            )
        _check_coordinates(points)
        if len(set(points)) < 3:
            raise InvalidGeofence(
                f"fewer than 3 distinct vertices ({len(set(points))}); a polygon needs 3"
            )
        for i in range(len(points)):
            if points[i] == points[(i + 1) % len(points)]:
                j = (i + 1) % len(points)
                raise InvalidGeofence(f"vertices {i + 1} and {j + 1} are the same point")
        centre = centre_of(points)
        distances = [haversine_m(*centre, lat, lon) for lat, lon in points]
        farthest = max(range(len(points)), key=distances.__getitem__)
        if distances[farthest] > MAX_POLYGON_RADIUS_M:
            raise InvalidGeofence(
                f"vertex {farthest + 1} is {distances[farthest] / 1000:.0f} km from the "
                f"polygon's centre; a geofence may reach at most "
                f"{MAX_POLYGON_RADIUS_M / 1000:.0f} km from it"
            )
        frame = LocalFrame(*centre)
        ring = [frame.to_local(lat, lon) for lat, lon in points]
        area = float(Polygon(ring).area)
        # Checked before crossings so that a line reads as a line, not as a fold; but only
        # with no area, as a symmetric bow-tie also sums to zero.
        if area < MIN_POLYGON_AREA_M2 and _collinear(ring):
            raise InvalidGeofence("all vertices lie on one line, so the polygon encloses no area")
        _check_simple(ring)
        if area < MIN_POLYGON_AREA_M2:
            raise InvalidGeofence(
                f"the polygon encloses {area:.2f} m²; a geofence must enclose at least "
                f"{MIN_POLYGON_AREA_M2:.0f} m²"
            )
        self.vertices: tuple[LatLon, ...] = tuple(points)
        self.frame = frame
        self.radius_m = distances[farthest]
        self._plane = PlanarPolygon(ring)

    def _near(self, lat: float, lon: float) -> bool:
        # Anything well beyond the farthest vertex is outside, and must be kept off the
        # plane: a point on the far side of the Earth would land back near its centre.
        return (
            haversine_m(self.frame.origin.lat, self.frame.origin.lon, lat, lon)
            <= self.radius_m * 1.01 + 10
        )

    def contains(self, lat: float, lon: float) -> bool:
        return self._near(lat, lon) and self._plane.contains(self.frame.to_local(lat, lon))

    def distance_outside_m(self, lat: float, lon: float) -> float:
        """How far a point is from the fence, in metres; 0 inside."""
        if self.contains(lat, lon):
            return 0.0
        from_centre = haversine_m(self.frame.origin.lat, self.frame.origin.lon, lat, lon)
        if from_centre > 4 * MAX_POLYGON_RADIUS_M:
            # Too far for the plane; no part of the fence is nearer than this.
            return from_centre - self.radius_m
        return self._plane.distance_to_boundary(self.frame.to_local(lat, lon))

    def leg_leaves(self, lat1: float, lon1: float, lat2: float, lon2: float) -> bool:
        """True when any part of the straight leg between two points is outside the fence."""
        if not (self._near(lat1, lon1) and self._near(lat2, lon2)):
            return True
        start, end = self.frame.to_local(lat1, lon1), self.frame.to_local(lat2, lon2)
        return self._plane.segment_leaves(start, end)


def validate_polygon(vertices: Sequence[LatLon]) -> tuple[LatLon, ...]:
    """Check (lat, lon) vertices can serve as a geofence; returns them with any repeated
    closing vertex dropped. Raises InvalidGeofence saying what is wrong."""
    return FencePolygon(vertices).vertices
