from __future__ import annotations

import math
from collections.abc import Sequence

import pytest

from backend.safety import (
    InvalidGeofence,
    LocalFrame,
    haversine_m,
    point_in_polygon,
    segment_leaves_polygon,
    segment_relation,
    validate_polygon,
)
from backend.safety.geometry import FencePolygon, PlanarPolygon
from common.geodesy import WGS84_A_M, WGS84_F
from tests.unit.safety.shapes import FRAME, U_SHAPE

E2 = WGS84_F * (2 - WGS84_F)


def meridian_arc_m(lat1: float, lat2: float, steps: int = 1000) -> float:
    """Exact-enough ellipsoidal meridian arc, by Simpson's rule over the radius of curvature."""

    def radius(phi: float) -> float:
        return WGS84_A_M * (1 - E2) / math.pow(1 - E2 * math.sin(phi) ** 2, 1.5)

    a, b = math.radians(lat1), math.radians(lat2)
    h = (b - a) / steps
    total = radius(a) + radius(b)
    total += sum((4 if i % 2 else 2) * radius(a + i * h) for i in range(1, steps))
    return total * h / 3


# --- Earth ----------------------------------------------------------------------------------


def test_haversine_one_degree_of_latitude_on_the_mean_sphere() -> None:
    assert haversine_m(0, 0, 1, 0) == pytest.approx(111_195.08, abs=0.01)
    assert haversine_m(10, 20, 10, 20) == 0


def test_haversine_across_the_antimeridian_is_short() -> None:
    assert haversine_m(0, 179.99, 0, -179.99) == pytest.approx(2_223.9, abs=0.1)


@pytest.mark.parametrize("lat", [0.0, 45.0, 70.0])
def test_local_north_matches_the_meridian_arc_over_10_km(lat: float) -> None:
    frame = LocalFrame(lat, 8.0)
    top = lat + 0.09  # about 10 km
    east, north = frame.to_local(top, 8.0)
    assert abs(east) < 1e-6
    assert north == pytest.approx(meridian_arc_m(lat, top), abs=0.01)


def test_local_east_matches_the_equator_arc_over_10_km() -> None:
    frame = LocalFrame(0.0, 0.0)
    dlon = 0.09
    east, north = frame.to_local(0.0, dlon)
    assert north == pytest.approx(0.0, abs=1e-6)
    # The equator is a circle of radius a, so the arc length is exact.
    assert east == pytest.approx(WGS84_A_M * math.radians(dlon), abs=0.01)


@pytest.mark.parametrize(
    ("lat", "lon"), [(0.0, 0.0), (47.0, 8.0), (-33.9, 151.2), (65.0, -18.0), (10.0, 179.95)]
)
def test_local_plane_round_trips_to_a_millimetre_over_10_km(lat: float, lon: float) -> None:
    frame = LocalFrame(lat, lon)
    for east, north in [(10_000, 0), (0, -10_000), (7_000, 7_000), (-6_000, 8_000)]:
        back = frame.to_local(*frame.to_geo(east, north))
        assert math.dist(back, (east, north)) < 1e-3
        # The plane's distances agree with the haversine's to its 0.6% sphere error.
        p = frame.to_geo(east, north)
        assert haversine_m(lat, lon, *p) == pytest.approx(math.hypot(east, north), rel=6e-3)


def test_local_plane_spans_the_antimeridian() -> None:
    frame = LocalFrame(0.0, 179.99)
    east, north = frame.to_local(0.0, -179.99)
    assert east == pytest.approx(WGS84_A_M * math.radians(0.02), abs=0.01)
    lat, lon = frame.to_geo(east, north)
    assert lat == pytest.approx(0.0, abs=1e-9)
    assert lon == pytest.approx(-179.99, abs=1e-9)


# --- Plane ----------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("point", "inside"),
    [
        ((50, 250), True),  # west arm
        ((250, 250), True),  # east arm
        ((150, 50), True),  # base
        ((150, 250), False),  # in the notch
        ((150, 150), False),  # in the notch, just above its floor
        ((-1, 150), False),
        ((350, 50), False),
        ((150, 100), True),  # on the notch floor: boundary counts as inside
        ((300, 300), True),  # a corner
    ],
)
def test_point_in_concave_polygon(point: tuple[float, float], inside: bool) -> None:
    assert point_in_polygon(point, U_SHAPE) is inside


def test_leg_across_the_notch_leaves_although_both_ends_are_inside() -> None:
    assert point_in_polygon((50, 250), U_SHAPE)
    assert point_in_polygon((250, 250), U_SHAPE)
    assert segment_leaves_polygon((50, 250), (250, 250), U_SHAPE)


@pytest.mark.parametrize(
    ("a", "b"),
    [
        ((50, 50), (250, 50)),  # along the base, under the notch
        ((0, 0), (300, 0)),  # along an edge
        ((100, 100), (200, 100)),  # along the notch floor
        ((50, 250), (50, 250)),  # no length
        ((20, 20), (100, 300)),  # ends on the inner corner of the west arm
    ],
)
def test_legs_that_stay_inside(a: tuple[float, float], b: tuple[float, float]) -> None:
    assert not segment_leaves_polygon(a, b, U_SHAPE)


def test_leg_grazing_a_reflex_corner_stays_inside() -> None:
    l_shape = [(0, 0), (200, 0), (200, 100), (100, 100), (100, 200), (0, 200)]
    # Through the inner corner (100, 100) exactly: inside on both sides of it.
    assert not segment_leaves_polygon((50, 150), (150, 50), l_shape)
    # A little further out it cuts across the missing quarter.
    assert segment_leaves_polygon((50, 190), (190, 50), l_shape)


def test_leg_across_the_notch_mouth_leaves() -> None:
    assert segment_leaves_polygon((100, 300), (200, 300), U_SHAPE)
    assert segment_leaves_polygon((50, 250), (350, 250), U_SHAPE)  # ends outside


def test_banded_index_agrees_with_a_plain_ray_cast() -> None:
    star = [
        ((5000 if i % 2 else 4000) * math.cos(a), (5000 if i % 2 else 4000) * math.sin(a))
        for i in range(200)
        for a in [2 * math.pi * i / 200]
    ]
    plane = PlanarPolygon(star)
    for i in range(-55, 56):
        for j in range(-55, 56):
            p = (i * 97.3, j * 101.7)
            x, y = p
            plain = False
            for (xi, yi), (xj, yj) in zip(star, star[1:] + star[:1], strict=True):
                if (yi > y) != (yj > y) and x < (xj - xi) * (y - yi) / (yj - yi) + xi:
                    plain = not plain
            assert plane.contains(p) is plain, p


def test_segment_relations() -> None:
    assert segment_relation((0, 0), (2, 2), (0, 2), (2, 0)) == "cross"
    assert segment_relation((0, 0), (2, 0), (1, 0), (1, 5)) == "touch"
    assert segment_relation((0, 0), (2, 0), (1, 0), (3, 0)) == "overlap"
    assert segment_relation((0, 0), (2, 0), (3, 0), (4, 0)) is None
    assert segment_relation((0, 0), (2, 0), (0, 1), (2, 1)) is None


# --- Polygon validation ---------------------------------------------------------------------


def deg(points: Sequence[tuple[float, float]]) -> list[tuple[float, float]]:
    """Metres on the shared plane to (lat, lon)."""
    return [FRAME.to_geo(e, n) for e, n in points]


@pytest.mark.parametrize(
    ("vertices", "reason"),
    [
        (deg([(0, 0), (100, 100), (100, 0), (0, 100)]), "edges 1 and 3 cross"),
        (deg([(0, 0), (100, 100)]), "fewer than 3 distinct vertices"),
        (deg([(0, 0), (0, 0), (100, 100), (100, 100)]), "fewer than 3 distinct vertices"),
        (deg([(0, 0), (0, 0), (100, 0), (0, 100)]), "vertices 1 and 2 are the same point"),
        ([(47.0, 8.0), (91.0, 8.0), (47.0, 8.001)], "vertex 2 latitude 91.0 is outside -90..90"),
        ([(47.0, 8.0), (47.0, 181.0), (47.001, 8.0)], "vertex 2 longitude 181.0 is outside"),
        ([(47.0, 8.0), (math.nan, 8.0), (47.001, 8.0)], "vertex 2 (nan, 8.0) is not a finite"),
        ([(47.0, 8.0), (47.0, math.inf), (47.001, 8.0)], "not a finite number"),
        (deg([(0, 0), (100, 0), (200, 0)]), "all vertices lie on one line"),
        ([(47.0, 8.0), (49.0, 8.0), (48.0, 9.0)], "km from the polygon's centre"),
        (
            # A figure eight pinched at one shared vertex.
            deg([(0, 0), (0, 200), (100, 100), (200, 0), (200, 200), (100, 100)]),
            "touch",
        ),
        (deg([(0, 0), (100, 0), (100, 100), (100, 50), (0, 100)]), "edges 2 and 3 fold back"),
        (deg([(0, 0), (10, 0), (10, 0.05), (0, 0.05)]), "encloses 0.50 m²"),
    ],
)
def test_invalid_polygons_are_rejected_with_the_reason(
    vertices: list[tuple[float, float]], reason: str
) -> None:
    with pytest.raises(InvalidGeofence) as caught:
        validate_polygon(vertices)
    assert reason in caught.value.message
    assert str(caught.value) == caught.value.message


def test_too_many_vertices() -> None:
    circle = [FRAME.to_geo(1000 * math.cos(a), 1000 * math.sin(a)) for a in _angles(1001)]
    with pytest.raises(InvalidGeofence, match="1001 vertices; a geofence may have at most 1000"):
        validate_polygon(circle)
    assert len(validate_polygon(circle[:1000])) == 1000


def _angles(n: int) -> list[float]:
    return [2 * math.pi * i / n for i in range(n)]


def test_repeated_closing_vertex_is_dropped() -> None:
    square = deg([(0, 0), (100, 0), (100, 100), (0, 100), (0, 0)])
    assert validate_polygon(square) == tuple(square[:4])


def test_polygon_across_the_antimeridian() -> None:
    fence = FencePolygon([(-0.1, 179.9), (-0.1, -179.9), (0.1, -179.9), (0.1, 179.9)])
    assert fence.contains(0, 180.0)
    assert fence.contains(0, -179.95)
    assert not fence.contains(0, 0)
    assert not fence.contains(0, 179.8)


def test_far_side_of_the_earth_is_outside() -> None:
    fence = FencePolygon(deg(U_SHAPE))
    # The antipode would land back on the tangent plane near the fence's centre.
    assert not fence.contains(-47.0, -172.0)
    assert fence.distance_outside_m(-47.0, -172.0) > 20_000_000
    assert fence.leg_leaves(*FRAME.to_geo(50, 50), -47.0, -172.0)


def test_distance_outside() -> None:
    fence = FencePolygon(deg(U_SHAPE))
    assert fence.distance_outside_m(*FRAME.to_geo(150, 250)) == pytest.approx(50, abs=0.01)
    assert fence.distance_outside_m(*FRAME.to_geo(350, 50)) == pytest.approx(50, abs=0.01)
    assert fence.distance_outside_m(*FRAME.to_geo(50, 50)) == 0
