"""Geometry for the safety rails: polygon tests on a local plane (common/geodesy.py's
LocalFrame, tangent to the Earth).

Geofences are small (at most MAX_POLYGON_RADIUS_M from their centre), so every polygon test
runs on a plane tangent to the Earth at the polygon's centre, in metres. On that plane a
polygon edge and a vehicle's straight leg are straight lines, which is how autopilots fly
between waypoints over these distances.

Numbers in error messages (edges, vertices) count from 1, as a person reading a list would.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from typing import Final

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


# --- Plane geometry -------------------------------------------------------------------------


def _point_segment_distance(p: XY, a: XY, b: XY) -> float:
    ax, ay = a
    dx, dy = b[0] - ax, b[1] - ay
    length2 = dx * dx + dy * dy
    t = 0.0 if length2 == 0 else ((p[0] - ax) * dx + (p[1] - ay) * dy) / length2
    t = max(0.0, min(1.0, t))
    return math.hypot(p[0] - (ax + t * dx), p[1] - (ay + t * dy))


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
    s1, s2 = _side(q1, q2, p1), _side(q1, q2, p2)
    s3, s4 = _side(p1, p2, q1), _side(p1, p2, q2)
    if s1 == s2 == s3 == s4 == 0:
        dx, dy = p2[0] - p1[0], p2[1] - p1[1]
        length = math.hypot(dx, dy)
        if length == 0:
            return "touch" if _point_segment_distance(p1, q1, q2) <= TOLERANCE_M else None
        # Positions of q's ends along p, in metres from p1.
        t1 = ((q1[0] - p1[0]) * dx + (q1[1] - p1[1]) * dy) / length
        t2 = ((q2[0] - p1[0]) * dx + (q2[1] - p1[1]) * dy) / length
        shared = min(length, max(t1, t2)) - max(0.0, min(t1, t2))
        if shared > TOLERANCE_M:
            return "overlap"
        return "touch" if shared >= -TOLERANCE_M else None
    if s1 * s2 < 0 and s3 * s4 < 0:
        return "cross"
    touching = (
        (s1 == 0 and _point_segment_distance(p1, q1, q2) <= TOLERANCE_M)
        or (s2 == 0 and _point_segment_distance(p2, q1, q2) <= TOLERANCE_M)
        or (s3 == 0 and _point_segment_distance(q1, p1, p2) <= TOLERANCE_M)
        or (s4 == 0 and _point_segment_distance(q2, p1, p2) <= TOLERANCE_M)
    )
    return "touch" if touching else None


def _edges(ring: Sequence[XY]) -> list[tuple[XY, XY]]:
    return [(ring[i], ring[(i + 1) % len(ring)]) for i in range(len(ring))]


Edge = tuple[XY, XY]


class PlanarPolygon:
    """A polygon on the plane, indexed for repeated tests.

    Edges are filed into horizontal bands by the span of y they cover, so a point test looks
    only at the edges level with the point: a 1000-vertex fence checked against a
    2000-waypoint mission stays well under a second.
    """

    __slots__ = ("_band_h", "_bands", "_edges", "_y0", "ring")

    def __init__(self, ring: Sequence[XY]) -> None:
        self.ring = tuple(ring)
        self._edges = _edges(self.ring)
        ys = [p[1] for p in self.ring]
        self._y0 = min(ys)
        count = max(1, len(self.ring) // 4)
        self._band_h = max((max(ys) - self._y0) / count, TOLERANCE_M)
        self._bands: list[list[Edge]] = [[] for _ in range(count)]
        for edge in self._edges:
            lo, hi = sorted((edge[0][1], edge[1][1]))
            for band in range(self._band(lo), self._band(hi) + 1):
                self._bands[band].append(edge)

    def _band(self, y: float) -> int:
        return max(0, min(len(self._bands) - 1, int((y - self._y0) // self._band_h)))

    def _edges_between(self, lo_y: float, hi_y: float) -> list[Edge]:
        first, last = self._band(lo_y), self._band(hi_y)
        if first == last:
            return self._bands[first]
        # An edge spanning several bands is filed in each; keep one copy.
        return list(dict.fromkeys(e for band in self._bands[first : last + 1] for e in band))

    def distance_to_boundary(self, p: XY) -> float:
        return min(_point_segment_distance(p, a, b) for a, b in self._edges)

    def _on_boundary(self, p: XY) -> bool:
        x, y = p
        for a, b in self._edges_between(y - TOLERANCE_M, y + TOLERANCE_M):
            if min(a[0], b[0]) - TOLERANCE_M <= x <= max(a[0], b[0]) + TOLERANCE_M and (
                _point_segment_distance(p, a, b) <= TOLERANCE_M
            ):
                return True
        return False

    def contains(self, p: XY) -> bool:
        """Ray casting (even-odd). Points on the boundary count as inside: a fence line drawn
        through a waypoint, or a leg flown along an edge, is within the fence."""
        x, y = p
        inside = False
        for (xi, yi), (xj, yj) in self._bands[self._band(y)]:
            if (yi > y) != (yj > y) and x < (xj - xi) * (y - yi) / (yj - yi) + xi:
                inside = not inside
        return inside or self._on_boundary(p)

    def segment_leaves(self, a: XY, b: XY) -> bool:
        """True when any part of the straight segment a→b lies outside the polygon.

        Both ends inside is not enough for a concave polygon: the segment can cut across a
        notch. The segment is split wherever it meets the boundary; between two such points
        it is wholly inside or wholly outside, so testing each piece's midpoint settles it.
        Extra split points cost a little time but never a wrong answer, so near-misses are
        kept.
        """
        if not (self.contains(a) and self.contains(b)):
            return True
        dx, dy = b[0] - a[0], b[1] - a[1]
        length = math.hypot(dx, dy)
        if length <= TOLERANCE_M:
            return False
        slack = TOLERANCE_M / length
        lo_x, hi_x = min(a[0], b[0]) - TOLERANCE_M, max(a[0], b[0]) + TOLERANCE_M
        lo_y, hi_y = min(a[1], b[1]) - TOLERANCE_M, max(a[1], b[1]) + TOLERANCE_M
        cuts = [0.0, 1.0]
        for c, d in self._edges_between(lo_y, hi_y):
            if max(c[0], d[0]) < lo_x or min(c[0], d[0]) > hi_x:
                continue
            if max(c[1], d[1]) < lo_y or min(c[1], d[1]) > hi_y:
                continue
            ex, ey = d[0] - c[0], d[1] - c[1]
            denom = dx * ey - dy * ex
            if denom != 0:
                t = ((c[0] - a[0]) * ey - (c[1] - a[1]) * ex) / denom
                u = ((c[0] - a[0]) * dy - (c[1] - a[1]) * dx) / denom
                edge_slack = TOLERANCE_M / max(math.hypot(ex, ey), TOLERANCE_M)
                if -slack <= t <= 1 + slack and -edge_slack <= u <= 1 + edge_slack:
                    cuts.append(min(1.0, max(0.0, t)))
            # Vertices on the segment: where it grazes a corner or runs along an edge.
            for v in (c, d):
                if _point_segment_distance(v, a, b) <= TOLERANCE_M:
                    t = ((v[0] - a[0]) * dx + (v[1] - a[1]) * dy) / (length * length)
                    cuts.append(min(1.0, max(0.0, t)))
        cuts.sort()
        for t0, t1 in itertools.pairwise(cuts):
            if (t1 - t0) * length <= TOLERANCE_M:
                continue
            mid = (t0 + t1) / 2
            if not self.contains((a[0] + mid * dx, a[1] + mid * dy)):
                return True
        return False


def distance_to_boundary(p: XY, ring: Sequence[XY]) -> float:
    return PlanarPolygon(ring).distance_to_boundary(p)


def point_in_polygon(p: XY, ring: Sequence[XY]) -> bool:
    """See PlanarPolygon.contains; build a PlanarPolygon once for repeated tests."""
    return PlanarPolygon(ring).contains(p)


def segment_leaves_polygon(a: XY, b: XY, ring: Sequence[XY]) -> bool:
    """See PlanarPolygon.segment_leaves; build a PlanarPolygon once for repeated tests."""
    return PlanarPolygon(ring).segment_leaves(a, b)


def signed_area(ring: Sequence[XY]) -> float:
    return sum(a[0] * b[1] - b[0] * a[1] for a, b in _edges(ring)) / 2


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
    """No two edges may meet except neighbours at their shared vertex.

    Edges are swept in order of their west end, so only edges whose east-west extents
    overlap are compared: about n log n for the shapes people draw, rather than n².
    """
    n = len(ring)
    for i in range(n):
        _check_neighbours(ring, i, (i + 1) % n)
    edges = _edges(ring)
    order = sorted(range(n), key=lambda i: min(edges[i][0][0], edges[i][1][0]))
    for pos, i in enumerate(order):
        a, b = edges[i]
        east_end = max(a[0], b[0]) + TOLERANCE_M
        lo_y, hi_y = min(a[1], b[1]) - TOLERANCE_M, max(a[1], b[1]) + TOLERANCE_M
        for j in order[pos + 1 :]:
            c, d = edges[j]
            if min(c[0], d[0]) > east_end:
                break
            if max(c[1], d[1]) < lo_y or min(c[1], d[1]) > hi_y:
                continue
            first, second = sorted((i, j))
            if (second - first) in (1, n - 1):
                continue  # neighbours, checked above
            relation = segment_relation(a, b, c, d)
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
        area = abs(signed_area(ring))
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
