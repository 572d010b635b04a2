"""The fleet split on five shapes and fleets of 2 to 8 drones: the parts do not overlap,
their union is the area, the photos of all parts cover it, and the slowest drone's time
(transit, part and way home) is at most 1.05 x the mean."""

from __future__ import annotations

import itertools

import pytest
import shapely
from shapely.geometry import Polygon, box

from backend.survey.planning.camera import calculate, preset
from backend.survey.planning.coverage import covered_fraction, footprints
from backend.survey.planning.planner import PlanError
from backend.survey.planning.split import Drone, split

CALC = calculate(
    preset("sony_a6000_16mm"), altitude_m=80, side_overlap_pct=70, front_overlap_pct=80
)

SHAPES = {
    "square": box(0, 0, 800, 800),
    "L": Polygon([(0, 0), (700, 0), (700, 250), (250, 250), (250, 700), (0, 700)]),
    "U": Polygon(
        [(0, 0), (700, 0), (700, 600), (500, 600), (500, 200), (200, 200), (200, 600), (0, 600)]
    ),
    "triangle": Polygon([(0, 0), (900, 100), (300, 700)]),
    "thin": box(0, 0, 2500, 80),
}


def _fleet(n: int) -> list[Drone]:
    # Drones waiting in a row south-west of the area, each to come home where it starts.
    return [Drone(f"d{i}", (-150.0 + 40 * i, -100.0), (-150.0 + 40 * i, -100.0)) for i in range(n)]


@pytest.mark.parametrize("n", [2, 3, 5, 8])
@pytest.mark.parametrize("name", list(SHAPES))
def test_parts_tile_the_area_and_balance_the_drones(name: str, n: int) -> None:
    area = SHAPES[name]
    parts = split(area, CALC, _fleet(n), angle_deg=0)
    assert [p.drone.name for p in parts] == [f"d{i}" for i in range(n)]
    for a, b in itertools.combinations(parts, 2):
        assert a.area.intersection(b.area).area < 1e-6
    union = shapely.union_all([p.area for p in parts])
    assert union.symmetric_difference(area).area < 1e-6 * area.area
    times = [p.total_s for p in parts]
    assert max(times) <= 1.05 * sum(times) / n
    shots = [
        f
        for p in parts
        for f in footprints(p.plan, CALC.lane_spacing_m * 1.0001, CALC.trigger_distance_m * 1.0001)
    ]
    assert covered_fraction(area, shots) == pytest.approx(1.0, abs=1e-9)


def test_split_counts_each_drones_transit_and_way_home() -> None:
    # One drone starts far away: it gets the smaller part.
    drones = [
        Drone("near", (0.0, -50.0), (0.0, -50.0)),
        Drone("far", (4000.0, -50.0), (4000.0, -50.0)),
    ]
    parts = split(SHAPES["square"], CALC, drones)
    near, far = parts
    assert far.transit_s + far.home_s > near.transit_s + near.home_s
    assert far.area.area < near.area.area
    assert max(near.total_s, far.total_s) <= 1.05 * (near.total_s + far.total_s) / 2


def test_a_drone_chosen_twice_is_refused() -> None:
    with pytest.raises(PlanError, match="each drone may be chosen once"):
        split(SHAPES["square"], CALC, [_fleet(1)[0], _fleet(1)[0]])


def test_no_drone_is_refused() -> None:
    with pytest.raises(PlanError, match="choose at least one drone"):
        split(SHAPES["square"], CALC, [])
