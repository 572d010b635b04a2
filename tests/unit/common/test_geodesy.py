"""common/geodesy.py against published reference values and PROJ, and one argument order
(positions in as lat, lon; local offsets as east, north) for every part that uses it."""

from __future__ import annotations

import math
import re
from pathlib import Path

import pytest
from pyproj import Geod, Transformer

import backend.safety
import simulator
from common.geodesy import EARTH_MEAN_RADIUS_M, GeoPoint, LocalFrame, centre_of, haversine_m
from gcs.launcher import VEHICLE_SPACING_M, FleetPlan
from simulator import DEFAULT_HOME, Copter

ROOT = Path(__file__).resolve().parents[3]
WGS84 = Geod(ellps="WGS84")
MEAN_SPHERE = Geod(a=EARTH_MEAN_RADIUS_M, b=EARTH_MEAN_RADIUS_M)


def proj_enu(origin: GeoPoint, lat: float, lon: float, alt: float) -> tuple[float, float, float]:
    """PROJ's own geodetic -> ECEF -> topocentric (east, north, up)."""
    pipeline = Transformer.from_pipeline(
        "+proj=pipeline +step +proj=cart +ellps=WGS84 +step +proj=topocentric +ellps=WGS84 "
        f"+lat_0={origin.lat} +lon_0={origin.lon} +h_0={origin.alt}"
    )
    east, north, up = pipeline.transform(lon, lat, alt)
    return east, north, up


# --- Reference values -----------------------------------------------------------------------


def test_enu_of_the_matterhorn_from_zermatt() -> None:
    # MathWorks' geodetic2enu example: the Matterhorn seen from Zermatt, in metres,
    # published to 0.1 m as xEast = -7134.8, yNorth = -4556.3, zUp = 2852.4.
    zermatt = LocalFrame(46.017, 7.750, 1673.0)
    enu = zermatt.to_enu(45.976, 7.658, 4531.0)
    assert enu == pytest.approx((-7134.8, -4556.3, 2852.4), abs=0.05)
    back = zermatt.from_enu(*enu)
    assert (back.lat, back.lon, back.alt) == pytest.approx((45.976, 7.658, 4531.0), abs=1e-6)


@pytest.mark.parametrize(
    ("origin", "target"),
    [
        (GeoPoint(46.017, 7.750, 1673.0), GeoPoint(45.976, 7.658, 4531.0)),
        (GeoPoint(-35.363262, 149.165237, 584.0), GeoPoint(-35.35, 149.18, 700.0)),
        (GeoPoint(0.0, 179.99, 0.0), GeoPoint(0.01, -179.99, 50.0)),  # across the antimeridian
        (GeoPoint(78.2, 15.6, 10.0), GeoPoint(78.9, 11.9, 0.0)),  # Svalbard, ~90 km
    ],
)
def test_enu_matches_proj_to_a_micrometre(origin: GeoPoint, target: GeoPoint) -> None:
    frame = LocalFrame(origin.lat, origin.lon, origin.alt)
    ours = frame.to_enu(target.lat, target.lon, target.alt)
    assert ours == pytest.approx(proj_enu(origin, target.lat, target.lon, target.alt), abs=1e-6)


def test_haversine_is_the_great_circle_on_the_mean_sphere() -> None:
    # Vincenty's Flinders Peak -> Buninyong (Geoscience Australia): 54 972.271 m on the
    # ellipsoid. The mean sphere is within its 0.6% of that, and equal to PROJ's own
    # great circle on that sphere.
    flinders = (-(37 + 57 / 60 + 3.72030 / 3600), 144 + 25 / 60 + 29.52440 / 3600)
    buninyong = (-(37 + 39 / 60 + 10.15610 / 3600), 143 + 55 / 60 + 35.38390 / 3600)
    (lat1, lon1), (lat2, lon2) = flinders, buninyong
    assert WGS84.inv(lon1, lat1, lon2, lat2)[2] == pytest.approx(54_972.271, abs=1e-3)
    distance = haversine_m(lat1, lon1, lat2, lon2)
    assert distance == pytest.approx(54_972.271, rel=6e-3)
    assert distance == pytest.approx(MEAN_SPHERE.inv(lon1, lat1, lon2, lat2)[2], abs=1e-6)


@pytest.mark.parametrize("azimuth", [0.0, 45.0, 90.0, 200.0, 315.0])
def test_local_plane_follows_the_geodesic_over_a_kilometre(azimuth: float) -> None:
    # A point 1 km along a WGS84 geodesic lies 1 km from the origin on the tangent plane,
    # in the geodesic's direction, to well under a millimetre.
    origin = GeoPoint(-35.363262, 149.165237)
    frame = LocalFrame(origin.lat, origin.lon)
    lon, lat, _ = WGS84.fwd(origin.lon, origin.lat, azimuth, 1000.0)
    east, north = frame.to_local(lat, lon)
    heading = math.radians(azimuth)
    assert (east, north) == pytest.approx(
        (1000 * math.sin(heading), 1000 * math.cos(heading)), abs=1e-3
    )
    assert frame.to_geo(east, north) == pytest.approx((lat, lon), abs=1e-12)


# --- One order everywhere -------------------------------------------------------------------


def test_every_part_uses_the_one_frame_and_point() -> None:
    assert backend.safety.LocalFrame is simulator.LocalFrame is LocalFrame
    assert backend.safety.GeoPoint is simulator.GeoPoint is GeoPoint
    assert backend.safety.haversine_m is haversine_m


def test_positions_go_in_as_lat_lon_and_offsets_come_out_as_east_north() -> None:
    frame = LocalFrame(DEFAULT_HOME.lat, DEFAULT_HOME.lon, DEFAULT_HOME.alt)
    # 300 m east and 100 m north of home, so a swapped order cannot pass.
    lat, lon = frame.to_geo(300.0, 100.0)
    assert lat > DEFAULT_HOME.lat
    assert lon > DEFAULT_HOME.lon
    assert frame.to_local(lat, lon) == pytest.approx((300.0, 100.0), abs=1e-6)
    assert frame.to_enu(lat, lon, DEFAULT_HOME.alt)[:2] == pytest.approx((300.0, 100.0), abs=1e-6)
    # The geofence's plane, built on the same frame.
    fence = backend.safety.FencePolygon(
        [frame.to_geo(e, n) for e, n in [(250, 50), (350, 50), (350, 150), (250, 150)]]
    )
    assert fence.contains(lat, lon)
    assert not fence.contains(*frame.to_geo(100.0, 300.0))
    # The simulator keeps ArduPilot's north-east order internally, by keyword.
    copter = Copter(DEFAULT_HOME)
    point = copter.geo_of(north=100.0, east=300.0)
    assert (point.lat, point.lon, point.alt) == (lat, lon, 584.0)
    assert copter.ne_of(lat, lon) == pytest.approx((100.0, 300.0), abs=1e-6)
    # The launcher sets its vehicles in a row to the east.
    plan = FleetPlan(home=(DEFAULT_HOME.lat, DEFAULT_HOME.lon, DEFAULT_HOME.alt))
    second = plan.vehicle_home(2)
    assert frame.to_local(second[0], second[1]) == pytest.approx(
        (2 * VEHICLE_SPACING_M, 0.0), abs=1e-6
    )


# The hand-written geodesy this module replaced, by its tell-tale names and constants.
_HAND_WRITTEN = re.compile(
    r"class (LocalFrame|GeoPoint)\b|def (haversine\w*|to_local|to_geo|to_global)\("
    r"|METRES_PER_DEGREE|LOCATION_SCALING_FACTOR|6_?378_?137|298\.257"
    r"|\b111_?3\d\d\b|radians\(lat\b"  # metres per degree; trigonometry on a latitude
)


def test_no_other_module_does_its_own_geodesy() -> None:
    found = [
        f"{path.relative_to(ROOT)}: {match.group(0)}"
        for package in ("protocol", "common", "vehicle_agents", "simulator", "backend", "gcs")
        for path in (ROOT / package).rglob("*.py")
        if path != ROOT / "common" / "geodesy.py"
        for match in _HAND_WRITTEN.finditer(path.read_text(encoding="utf-8"))
    ]
    assert found == []


def test_the_centre_of_points_across_the_antimeridian_is_on_it() -> None:
    lat, lon = centre_of([(10.0, 179.0), (10.0, -179.0), (12.0, 180.0)])
    assert abs(lon) == pytest.approx(180.0)
    assert 10.0 < lat < 12.0
    assert centre_of([(47.0, 8.0), (47.0, 8.0)]) == pytest.approx((47.0, 8.0))
