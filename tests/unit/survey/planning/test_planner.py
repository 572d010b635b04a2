"""The lane planner on convex, L, U, holed, thin and zone-straddling areas: the photos'
footprints cover the area at the requested overlaps, lanes keep out of holes, and bad areas
are refused with a message saying what to change."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from pymavlink.dialects.v20 import ardupilotmega as mavlink2
from shapely import affinity
from shapely.geometry import LineString, Polygon, box

from backend.survey.planning.bound import lower_bound_m
from backend.survey.planning.camera import calculate, preset
from backend.survey.planning.coverage import coverage, covered_fraction, footprints, swaths
from backend.survey.planning.geo import polygon_from_geojson
from backend.survey.planning.lanes import Lane
from backend.survey.planning.mission import mission_items
from backend.survey.planning.planner import PlanError, plan_lanes
from backend.survey.planning.report import best_angle, flight_time_s
from common.geodesy import GeoPoint
from tests.support.survey_shapes import SHAPES, shape

CALC = calculate(
    preset("sony_a6000_16mm"), altitude_m=100, side_overlap_pct=70, front_overlap_pct=80
)


@pytest.mark.parametrize("angle", [0.0, 30.0, 90.0])
@pytest.mark.parametrize("name", [*SHAPES, "zone-straddling"])
def test_footprints_cover_the_whole_area(name: str, angle: float) -> None:
    area = shape(name)
    plan = plan_lanes(area, CALC, angle_deg=angle)
    footprint, at_overlaps = coverage(plan, area, CALC)
    assert footprint == pytest.approx(1.0, abs=1e-9)
    if name != "holed":
        # Shrunk to spacing x trigger distance, the footprints still tile the area: every
        # point is seen with the requested side and front overlaps.
        assert at_overlaps == pytest.approx(1.0, abs=1e-9)


@pytest.mark.parametrize("angle", [0.0, 15.0, 30.0, 45.0, 60.0])
def test_no_lane_turnaround_or_transit_enters_a_hole(angle: float) -> None:
    # Holes are no-fly areas: lanes are cut short of them by the turnaround they need, and
    # the lanes are ordered so that no straight transit crosses one (they may run along
    # its edge).
    area = SHAPES["holed"]
    inside = Polygon(area.interiors[0]).buffer(-0.01)
    plan = plan_lanes(area, CALC, angle_deg=angle)
    for a, b in zip(plan.path, plan.path[1:], strict=False):
        assert not LineString([a, b]).intersects(inside)


def _random_holed_area(seed: int) -> Polygon:
    rng = np.random.default_rng(seed)
    outer = box(0, 0, rng.uniform(300, 900), rng.uniform(300, 900))
    holes: list[Polygon] = []
    for _ in range(3):
        x, y = rng.uniform(60, outer.bounds[2] - 60), rng.uniform(60, outer.bounds[3] - 60)
        r = rng.uniform(15, 60)
        hole = affinity.rotate(
            box(x - r, y - r * rng.uniform(0.3, 1), x + r, y + r), rng.uniform(0, 90)
        )
        if hole.within(outer.buffer(-5)) and all(hole.distance(h) > 5 for h in holes):
            holes.append(hole)
    return Polygon(outer.exterior, [h.exterior for h in holes])


@pytest.mark.parametrize("turnaround", [10.0, 25.0])
@pytest.mark.parametrize("seed", range(8))
def test_lanes_and_turnarounds_keep_out_of_random_holes(seed: int, turnaround: float) -> None:
    # Lanes end a turnaround short of a hole; a piece shorter than a trigger distance
    # beside one takes its photos where neither turnaround reaches into it.
    area = _random_holed_area(seed)
    inside = [Polygon(ring).buffer(-0.01) for ring in area.interiors]
    for angle in (0.0, 20.0, 70.0):
        plan = plan_lanes(area, CALC, angle_deg=angle, turnaround_m=turnaround)
        for i in range(len(plan.lanes)):
            turn_in, start, end, turn_out = plan.path[4 * i : 4 * i + 4]
            flown = LineString([turn_in, start, end, turn_out])
            assert not any(flown.intersects(hole) for hole in inside)


@pytest.mark.parametrize("angle", [float(a) for a in range(0, 180, 15)])
@pytest.mark.parametrize("name", [*SHAPES, "zone-straddling"])
def test_path_is_within_five_percent_of_the_lower_bound(name: str, angle: float) -> None:
    # The bound (survey/bound.py) is what any lane plan on these rows must fly, the
    # unavoidable transits across a U's arms or around a hole included; it is checked
    # against the exact best plan in tests/unit/survey/planning/test_bound.py.
    area = shape(name)
    plan = plan_lanes(area, CALC, angle_deg=angle)
    bound = lower_bound_m(area, CALC, angle, plan.turnaround_m)
    assert bound <= plan.path_length_m + 1e-6
    assert plan.path_length_m <= 1.05 * bound


def test_lanes_stop_half_a_trigger_distance_inside_the_area() -> None:
    # A photo's footprint at the overlaps reaches half a trigger distance along the lane,
    # so flying on to the edge would be wasted: a 1000 m square's lanes are 1000 - t long.
    plan = plan_lanes(box(0, 0, 1000, 1000), CALC, angle_deg=0)
    for lane in plan.lanes:
        assert lane.length_m == pytest.approx(1000 - CALC.trigger_distance_m)
        xs = sorted(x for x, _ in (lane.start, lane.end))
        assert xs == pytest.approx(
            [CALC.trigger_distance_m / 2, 1000 - CALC.trigger_distance_m / 2]
        )


@pytest.mark.parametrize("name", ["convex", "U", "holed"])
def test_the_lane_swaths_cover_what_every_photo_footprint_covers(name: str) -> None:
    # The coverage check unions footprints lane by lane; with every third photo dropped the
    # footprints leave gaps along the lanes, and both ways still agree to the square metre.
    area = SHAPES[name]
    plan = plan_lanes(area, CALC, angle_deg=30.0)
    sparse = dataclasses.replace(
        plan, lanes=tuple(Lane(x.start, x.end, x.photos[::3]) for x in plan.lanes)
    )
    for p in (plan, sparse):
        for side, frontal in (
            (CALC.footprint_side_m, CALC.footprint_frontal_m),
            (CALC.lane_spacing_m, CALC.trigger_distance_m),
        ):
            every = covered_fraction(area, footprints(p, side, frontal))
            assert covered_fraction(area, swaths(p, side, frontal)) == pytest.approx(
                every, abs=1e-9
            )
    assert (
        covered_fraction(area, swaths(sparse, CALC.lane_spacing_m, CALC.trigger_distance_m)) < 0.9
    )


@pytest.mark.parametrize("name", ["convex", "L", "holed"])
def test_the_angle_search_finds_the_angle_planning_every_one_finds(name: str) -> None:
    area = SHAPES[name]
    times = {
        float(a): flight_time_s(plan_lanes(area, CALC, angle_deg=a, turnaround_m=10), 10.0)
        for a in range(0, 180, 5)
    }
    fastest = min(times, key=lambda a: (times[a], a))
    assert best_angle(area, CALC, 10.0, turnaround_m=10) == fastest


def test_a_concave_area_is_flown_without_a_detour_at_its_inner_corner() -> None:
    # The L's rows shrink from 600 m to 200 m: flown from the arm's far corner, the lane
    # after the step starts where the one before it ended; flown the other way it would
    # cross 400 m back.
    plan = plan_lanes(SHAPES["L"], CALC, angle_deg=0)
    legs = [math.dist(a, b) for a, b in zip(plan.path[3::4], plan.path[4::4], strict=False)]
    assert max(legs) < CALC.lane_spacing_m * 1.5


def test_turnarounds_lie_outside_the_area() -> None:
    area = box(0, 0, 500, 500)
    plan = plan_lanes(area, CALC, angle_deg=0, turnaround_m=10)
    for i in range(len(plan.lanes)):
        for turn in (plan.path[4 * i], plan.path[4 * i + 3]):
            assert area.exterior.distance(
                LineString([turn, turn])
            ) >= 10 - 1e-6 or not area.contains(LineString([turn, turn]))


def test_automatic_angle_runs_lanes_along_a_long_thin_area() -> None:
    area = affinity.rotate(box(0, 0, 2000, 120), 40, origin=(0, 0))
    angle = best_angle(area, CALC, 10.0, turnaround_m=10)
    assert angle == pytest.approx(40, abs=5)
    plan = plan_lanes(area, CALC, angle_deg=angle)
    assert flight_time_s(plan, 10.0) < flight_time_s(
        plan_lanes(area, CALC, angle_deg=angle + 90), 10.0
    )


def test_mission_items_trigger_on_distance_along_each_lane() -> None:
    polygon, frame = polygon_from_geojson(
        {
            "type": "Polygon",
            "coordinates": [
                [[8.0, 47.0], [8.005, 47.0], [8.005, 47.004], [8.0, 47.004], [8.0, 47.0]]
            ],
        }
    )
    plan = plan_lanes(polygon, CALC)
    items = mission_items(plan, frame, CALC.altitude_m, takeoff=GeoPoint(46.999, 8.0))
    commands = [item.command for item in items]
    assert commands[0] == mavlink2.MAV_CMD_NAV_TAKEOFF
    assert commands[-1] == mavlink2.MAV_CMD_NAV_RETURN_TO_LAUNCH
    triggers = [item for item in items if item.command == mavlink2.MAV_CMD_DO_SET_CAM_TRIGG_DIST]
    assert len(triggers) == 2 * len(plan.lanes)
    assert [t.param1 for t in triggers[:2]] == [pytest.approx(CALC.trigger_distance_m), 0.0]
    # QGC's "trigger once" on both: a photo at each lane's entry and at its exit
    assert all(t.param3 == 1 for t in triggers)
    # ArduPilot runs a "do" command once the waypoint before it is reached: the camera
    # starts at the lane's entry and stops at its exit, each following its waypoint.
    for i, item in enumerate(items):
        if item.command == mavlink2.MAV_CMD_DO_SET_CAM_TRIGG_DIST:
            assert items[i - 1].command == mavlink2.MAV_CMD_NAV_WAYPOINT
    for item in items:
        if item.command == mavlink2.MAV_CMD_NAV_WAYPOINT:
            assert item.frame == mavlink2.MAV_FRAME_GLOBAL_RELATIVE_ALT
            assert item.alt == pytest.approx(CALC.altitude_m)
            assert 46.99 < item.lat < 47.01
            assert 7.99 < item.lon < 8.01
            # Yaw unset, as QGC writes it: PX4 faces along the lane (0 held it north).
            assert item.param4 is None
    assert items[0].param4 is None  # the take-off keeps its heading


def test_hover_and_capture_takes_one_image_at_each_photo_point() -> None:
    polygon, frame = polygon_from_geojson(
        {
            "type": "Polygon",
            "coordinates": [[[8.0, 47.0], [8.003, 47.0], [8.003, 47.003], [8.0, 47.0]]],
        }
    )
    plan = plan_lanes(polygon, CALC)
    items = mission_items(plan, frame, CALC.altitude_m, takeoff=None, hover=True)
    captures = [i for i in items if i.command == mavlink2.MAV_CMD_DO_DIGICAM_CONTROL]
    assert len(captures) == plan.photo_count
    # param5 "shoot" is 1: MISSION_ITEM_INT's x, unscaled, which our items hold as lat * 1e7
    assert all(round(c.lat * 1e7) == 1 for c in captures)
    # each capture follows the waypoint it is taken at, which holds for the camera to settle
    for i, capture in enumerate(items):
        if capture.command == mavlink2.MAV_CMD_DO_DIGICAM_CONTROL:
            assert items[i - 1].command == mavlink2.MAV_CMD_NAV_WAYPOINT
            assert items[i - 1].param1 > 0


@pytest.mark.parametrize(
    ("area", "message"),
    [
        (Polygon([(0, 0), (500, 500), (500, 0), (0, 500)]), r"Self-intersection\[250 250\]"),
        (box(0, 0, 50, 50), "smaller than one photo's footprint"),
        (Polygon(), "at least 3 distinct corners"),
        (
            Polygon([(0, 0), (500, 0), (500, 500)], [[(600, 0), (700, 0), (700, 100)]]),
            "not a valid polygon: Hole lies outside shell",
        ),
    ],
)
def test_invalid_areas_are_refused_saying_why(area: Polygon, message: str) -> None:
    with pytest.raises(PlanError, match=message):
        plan_lanes(area, CALC)


def test_holes_covering_the_whole_area_are_refused() -> None:
    area = Polygon(
        [(0, 0), (500, 0), (500, 500), (0, 500)], [[(0, 0), (500, 0), (500, 500), (0, 500)]]
    )
    with pytest.raises(PlanError, match="the holes cover the whole area"):
        plan_lanes(area, CALC)


def test_too_many_vertices_are_refused() -> None:
    ring = [
        (1000 * math.cos(t / 2000 * math.tau), 1000 * math.sin(t / 2000 * math.tau))
        for t in range(10_001)
    ]
    with pytest.raises(PlanError, match="at most 10000 are allowed"):
        plan_lanes(Polygon(ring), CALC)


@pytest.mark.parametrize(
    ("geometry", "message"),
    [
        ({"type": "Point", "coordinates": [0, 0]}, "type Polygon"),
        ({"type": "Polygon", "coordinates": [[[0, 0], [1, 1]]]}, "at least 4 positions"),
        (
            {"type": "Polygon", "coordinates": [[[0, 0], [0, 95], [1, 1], [0, 0]]]},
            "position 1 is not a longitude/latitude",
        ),
        (
            {"type": "Polygon", "coordinates": [[[0, 0], [1, 0], [1, 1], [0, 0]]]},
            "km from its centre",
        ),
    ],
)
def test_bad_geojson_is_refused_saying_why(geometry: dict[str, object], message: str) -> None:
    with pytest.raises(PlanError, match=message):
        polygon_from_geojson(geometry)
