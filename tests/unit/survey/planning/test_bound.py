"""The survey path's lower bound (backend/survey/planning/bound.py) against the exact best
order and directions of the lanes, found by dynamic programming over every order on small
areas and on random pieces: the bound is never above the best, and the planner's path is
never below the bound."""

from __future__ import annotations

import numpy as np
import pytest
from shapely.geometry import Polygon, box

from backend.survey.planning.bound import (
    end_distances,
    lower_bound,
    transit_bound_m,
    transit_distances,
)
from backend.survey.planning.camera import calculate, preset
from backend.survey.planning.planner import Piece, plan_lanes, row_pieces

# Low, so that small areas have several rows: lane spacing 22 m, trigger distance 9.8 m.
CALC = calculate(
    preset("sony_a6000_16mm"), altitude_m=50, side_overlap_pct=70, front_overlap_pct=80
)
TURNAROUND_M = 10.0

SMALL = {
    "square": box(0, 0, 150, 120),
    "L": Polygon([(0, 0), (160, 0), (160, 50), (50, 50), (50, 130), (0, 130)]),
    "U": Polygon(
        [(0, 0), (160, 0), (160, 150), (120, 150), (120, 60), (40, 60), (40, 150), (0, 150)]
    ),
    "holed": Polygon(
        [(0, 0), (150, 0), (150, 110), (0, 110)], [[(50, 35), (100, 35), (100, 75), (50, 75)]]
    ),
    "slanted": Polygon([(0, 0), (140, 30), (120, 140), (10, 110)]),
    "sliver": Polygon([(0, 0), (200, 0), (205, 30), (5, 30)]),
}


def _best_transits_m(distance: np.ndarray) -> float:
    """The least transits over all orders and directions (Held-Karp dynamic programming):
    best[mask][e] is the least transit having flown the pieces in mask, leaving at end e."""
    n = distance.shape[0] // 2
    best = np.full((1 << n, 2 * n), np.inf)
    for i in range(n):
        best[1 << i, 2 * i : 2 * i + 2] = 0.0
    for mask in range(1, 1 << n):
        here = best[mask]
        if not np.isfinite(here).any():
            continue
        entering = (here[:, None] + distance).min(axis=0)  # the least way into each end
        for j in range(n):
            if mask >> j & 1:
                continue
            # entered at one end, the piece is left at the other
            target = best[mask | 1 << j]
            target[2 * j] = min(target[2 * j], entering[2 * j + 1])
            target[2 * j + 1] = min(target[2 * j + 1], entering[2 * j])
    return float(best[-1].min())


def _best_plan_m(pieces: list[Piece], distance: np.ndarray) -> float:
    lanes = sum(max(0.0, b - a - CALC.trigger_distance_m) for a, b, _ in pieces)
    return lanes + 2 * TURNAROUND_M * len(pieces) + _best_transits_m(distance)


@pytest.mark.parametrize("angle", [0.0, 35.0, 90.0])
@pytest.mark.parametrize("name", list(SMALL))
def test_the_bound_is_below_the_best_plan_and_the_planner_above_the_bound(
    name: str, angle: float
) -> None:
    area = SMALL[name]
    # the same pieces and least transits (around holes) as the bound, every order tried
    pieces, distance = transit_distances(area, CALC, angle, TURNAROUND_M)
    assert 2 <= len(pieces) <= 13, "keep the exact search small"
    bound = lower_bound(area, CALC, angle, TURNAROUND_M).total_m
    best = _best_plan_m(pieces, distance)
    plan = plan_lanes(area, CALC, angle_deg=angle, turnaround_m=TURNAROUND_M, whole_area=False)
    assert bound <= best + 1e-6
    assert best <= plan.path_length_m + 1e-6
    # the 1-tree keeps the bound close to the best order, concave and holed areas included
    assert bound >= 0.95 * best


def test_the_bound_counts_the_unavoidable_transit_of_a_u() -> None:
    # A U's arms meet only at its base: a plan either crosses between the arms' tops or
    # goes back over the base, so its transits exceed one spacing per lane change; the
    # nearest-entry sum alone does not see that, the 1-tree does.
    area = SMALL["U"]
    pieces = row_pieces(area, CALC.lane_spacing_m, 0.0)
    distance = end_distances(pieces, CALC.trigger_distance_m, TURNAROUND_M)
    one_spacing_each = (len(pieces) - 1) * CALC.lane_spacing_m
    assert _best_transits_m(distance) > one_spacing_each + 20
    assert transit_bound_m(distance) > one_spacing_each + 20


@pytest.mark.parametrize("seed", range(30))
def test_the_transit_bound_is_below_the_best_order_on_random_pieces(seed: int) -> None:
    rng = np.random.default_rng(seed)
    n = int(rng.integers(2, 9))
    rows = rng.integers(0, 6, n).astype(float) * 20.0
    starts = rng.uniform(0, 300, n)
    lengths = rng.uniform(0, 200, n)  # some shorter than a trigger distance
    pieces = [(a, a + length, y) for a, length, y in zip(starts, lengths, rows, strict=True)]
    distance = end_distances(pieces, trigger_m=15.0, turnaround_m=float(rng.uniform(0, 20)))
    assert transit_bound_m(distance) <= _best_transits_m(distance) + 1e-6
