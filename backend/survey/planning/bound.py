"""The lower bound survey paths are held to: no lane plan on the planner's rows can be shorter.

The plans it bounds ("lane plans on these rows"): the area is cut into rows one lane spacing
wide at the grid angle (planner.row_pieces, the rows the planner flies); the part of the
area in a row's strip is one or more pieces, each an interval [a, b] along the row, cut
where a hole crosses the row's centre line. Each piece is flown as one straight lane on the
row's centre line, taking photos at most one trigger distance apart, in either direction;
every lane has a turnaround leg of `turnaround_m` in line with it at each end; straight
transits join one lane's exit turnaround to the next lane's entry turnaround, the pieces in
any order; and nothing enters a hole (a no-fly area). So a lane against a hole ends at
least a turnaround short of it, and what it must cover there ends max(0, turnaround - t/2)
short of the hole (planner.hole_margin_m; t is the trigger distance): the pieces are cut
there. The plan covers the pieces at the requested overlaps: every point lies in some
photo's footprint shrunk to one lane spacing by t (coverage.coverage's second figure).

The bound is the sum of three parts, each no more than what any such plan flies:

1. Lanes: a point of a piece strictly inside its strip is seen at the overlaps only by a
   photo on that row (another row's shrunk footprint ends at the strip's edge), within half
   a trigger distance t/2 of it along the row. So a piece's lane starts at or before
   a + t/2 and ends at or after b - t/2: it is at least (b - a - t) long, and 0 when the
   piece is shorter than t. Whatever a lane is longer than that, it is longer beyond the
   interval of those end positions; that overshoot is credited to the transits below.
2. Turnarounds: 2 x `turnaround_m` per lane.
3. Transits: a lane's exit turnaround point lies on its row at x_end +- turnaround_m, with
   x_end in the interval of minimal end positions (a single point b - t/2 for a piece
   longer than t; [b - t/2, a + t/2] for a shorter one), or beyond it by the lane's
   overshoot. A transit is at least the distance between its two end intervals, less the
   overshoots at its two ends (triangle inequality), and those overshoots were left out of
   part 1, so part 1 + part 3 may use the intervals' distances. The order and directions
   are a travelling-salesman path over the pieces' end points in which each piece's two
   ends are consecutive. Between two ends, the least transit is the distance between their
   intervals, and at least the shortest way between the intervals' middles that keeps out
   of the holes (through their corners) less the intervals' half-widths; the larger is
   used. The path's least length is bounded from below by Held and Karp's 1-tree
   bound (a spanning tree over the ends, each lane forced into it, with Lagrangian node
   weights; any weights give a valid bound, the subgradient steps only raise it) and by
   the simpler sum over pieces of the nearest end of another piece (every piece but the
   first is entered from another one). The larger of the two is taken. The 1-tree counts
   what no plan can avoid on a concave area: a U's arms or the two sides of a hole are
   joined only through the base, so some transit there is longer than one spacing.

It depends on the rows' positions (their grid offset), so it is the bound
for the planner's rows; area / spacing is no bound at all once lanes stop half a trigger
distance inside the area. tests/unit/survey/planning/test_bound.py checks it against the exact best
order, found by dynamic programming over all orders and directions on small areas.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import shapely
from shapely.geometry import LinearRing, Polygon

from backend.survey.planning.camera import CameraCalc
from backend.survey.planning.holes import crossings
from backend.survey.planning.planner import Piece, hole_margin_m, rotated_area, row_pieces

_FORCED = 1e7  # minus this on a lane's own edge keeps it in every spanning tree
_SUBGRADIENT_STEPS = 150
_MAX_HOLE_VERTICES = 400  # above this, transits are bounded straight (still a bound)


@dataclass(frozen=True, slots=True)
class Bound:
    """The lower bound and its parts, in metres."""

    lanes: int
    lanes_m: float
    turnarounds_m: float
    transits_m: float

    @property
    def total_m(self) -> float:
        return self.lanes_m + self.turnarounds_m + self.transits_m


def lower_bound(
    area: Polygon, calc: CameraCalc, angle_deg: float, turnaround_m: float, *, quick: bool = False
) -> Bound:
    """The least path length of any lane plan on the planner's rows (module docstring).
    `quick` leaves the 1-tree out: a looser bound, for pruning the angle search."""
    pieces, distance = transit_distances(area, calc, angle_deg, turnaround_m, quick=quick)
    trigger = calc.trigger_distance_m
    if len(pieces) < 2:
        transits = 0.0
    elif quick:
        transits = _nearest_entries_m(distance)
    else:
        transits = transit_bound_m(distance)
    return Bound(
        lanes=len(pieces),
        lanes_m=sum(max(0.0, b - a - trigger) for a, b, _ in pieces),
        turnarounds_m=2 * turnaround_m * len(pieces),
        transits_m=transits,
    )


def transit_distances(
    area: Polygon, calc: CameraCalc, angle_deg: float, turnaround_m: float, *, quick: bool = False
) -> tuple[list[Piece], np.ndarray]:
    """The pieces, and the least transit between each two of their ends (end_distances,
    raised to the way around the holes unless `quick`)."""
    trigger = calc.trigger_distance_m
    pieces = row_pieces(area, calc.lane_spacing_m, angle_deg, hole_margin_m(trigger, turnaround_m))
    distance = end_distances(pieces, trigger, turnaround_m)
    holes = list(rotated_area(area, angle_deg).interiors)
    if not quick and 0 < sum(len(ring.coords) for ring in holes) <= _MAX_HOLE_VERTICES:
        distance = np.maximum(distance, _around_holes(pieces, trigger, turnaround_m, holes))
    return pieces, distance


def lower_bound_m(area: Polygon, calc: CameraCalc, angle_deg: float, turnaround_m: float) -> float:
    return lower_bound(area, calc, angle_deg, turnaround_m).total_m


def _end_intervals(
    pieces: list[Piece], trigger_m: float, turnaround_m: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per end (piece i's west end at 2 i, east end at 2 i + 1), the interval [lo, hi] its
    turnaround point lies in on its row, and the row's y (part 3)."""
    half = trigger_m / 2
    lo, hi, ys = [], [], []
    for a, b, y in pieces:
        lo += [min(a + half, b - half) - turnaround_m, b - half + turnaround_m]
        hi += [a + half - turnaround_m, max(a + half, b - half) + turnaround_m]
        ys += [y, y]
    return np.array(lo), np.array(hi), np.array(ys)


def end_distances(pieces: list[Piece], trigger_m: float, turnaround_m: float) -> np.ndarray:
    """The least transit between each two pieces' ends: a (2n, 2n) matrix over the ends,
    piece i's west end at 2 i and its east end at 2 i + 1 (a transit leaves one and enters
    the other). Each end is the interval of its turnaround point's places (part 3)."""
    lo_, hi_, y_ = _end_intervals(pieces, trigger_m, turnaround_m)
    gap = np.maximum(0.0, np.maximum(lo_[:, None] - hi_[None, :], lo_[None, :] - hi_[:, None]))
    distance: np.ndarray = np.hypot(gap, y_[:, None] - y_[None, :])
    return distance


def _around_holes(
    pieces: list[Piece], trigger_m: float, turnaround_m: float, holes: Sequence[LinearRing]
) -> np.ndarray:
    """end_distances for plans that keep out of the holes (no-fly areas): the shortest way
    between two ends' middles that does not enter a hole (through the holes' corners,
    Floyd-Warshall over the straight lines that keep out), less half of each end's
    interval (moving an end along its interval changes that way by no more than it moves)."""
    lo, hi, ys = _end_intervals(pieces, trigger_m, turnaround_m)
    mids = np.column_stack([(lo + hi) / 2, ys])
    corners = np.array([c for ring in holes for c in ring.coords[:-1]])
    nodes = np.concatenate([mids, corners])
    straight = np.hypot(*(nodes[:, None, :] - nodes[None, :, :]).transpose(2, 0, 1))
    blocked = crossings(nodes, nodes, shapely.union_all([Polygon(ring) for ring in holes]))
    way = np.where(blocked, np.inf, straight)
    for k in range(len(nodes)):
        way = np.minimum(way, way[:, k, None] + way[None, k, :])
    m = len(mids)
    slack = (hi - lo) / 2
    around: np.ndarray = way[:m, :m] - slack[:, None] - slack[None, :]
    return around


def transit_bound_m(distance: np.ndarray) -> float:
    """A lower bound on the transits of the shortest path through all pieces, each flown
    from one end to the other: the larger of the nearest-entry and 1-tree bounds."""
    n = distance.shape[0] // 2
    if n < 2:
        return 0.0
    return max(_nearest_entries_m(distance), _one_tree_m(distance))


def _others(distance: np.ndarray) -> np.ndarray:
    """The distances with each piece's own two ends apart (no transit joins them)."""
    masked = distance.copy()
    idx = np.arange(distance.shape[0])
    masked[idx, idx ^ 1] = np.inf
    masked[idx, idx] = np.inf
    return masked


def _nearest_entries_m(distance: np.ndarray) -> float:
    """Every piece but the first is entered, at one of its ends, from another piece."""
    nearest = _others(distance).min(axis=1).reshape(-1, 2).min(axis=1)
    return float(nearest.sum() - nearest.max())


def _one_tree_m(distance: np.ndarray) -> float:
    """Held-Karp: the path is a cycle through the ends and one extra node joined to every
    end at no cost, using each lane's edge. For any node weights w, a cycle's length is at
    least the least 1-tree under costs d(u, v) + w(u) + w(v) less 2 x sum(w): a spanning
    tree over the ends (with each lane's edge, forced in by a large negative cost) and the
    extra node's two cheapest edges."""
    m = distance.shape[0]
    n = m // 2
    base = _others(distance)
    idx = np.arange(m)
    base[idx, idx ^ 1] = -_FORCED
    weights = np.zeros(m)
    best = -math.inf
    # An upper bound (a greedy path) scales the steps; it does not affect validity.
    upper = _greedy_path_m(distance)
    scale = 2.0
    stale = 0
    for _ in range(_SUBGRADIENT_STEPS):
        cost = base + weights[:, None] + weights[None, :]
        tree, degree = _spanning_tree(cost)
        two = np.argpartition(weights, 2)[:2]
        degree[two] += 1
        value = tree + float(weights[two].sum()) - 2 * float(weights.sum()) + n * _FORCED
        if value > best + 1e-9:
            best, stale = value, 0
        else:
            stale += 1
            if stale >= 10:
                scale, stale = scale / 2, 0
        step = degree - 2
        norm = float((step * step).sum())
        if norm == 0 or scale < 1e-4:
            break  # the 1-tree is a cycle: the bound is the optimum
        weights += scale * max(upper - value, 1e-3 * upper) / norm * step
    return max(best, 0.0)


def _spanning_tree(cost: np.ndarray) -> tuple[float, np.ndarray]:
    """Prim's algorithm on a dense matrix: the least spanning tree's cost and degrees."""
    m = cost.shape[0]
    inside = np.zeros(m, dtype=bool)
    inside[0] = True
    best = cost[0].copy()
    parent = np.zeros(m, dtype=int)
    degree = np.zeros(m)
    total = 0.0
    for _ in range(m - 1):
        best[inside] = np.inf
        j = int(np.argmin(best))
        total += float(best[j])
        degree[j] += 1
        degree[parent[j]] += 1
        inside[j] = True
        closer = cost[j] < best
        best = np.where(closer, cost[j], best)
        parent = np.where(closer, j, parent)
    return total, degree


def _greedy_path_m(distance: np.ndarray) -> float:
    """A feasible path's transits: from piece 0, the nearest unflown piece each time."""
    n = distance.shape[0] // 2
    done = np.zeros(n, dtype=bool)
    done[0] = True
    here, total = 1, 0.0
    for _ in range(n - 1):
        row = distance[here].reshape(-1, 2).copy()
        row[done] = np.inf
        piece, end = np.unravel_index(int(np.argmin(row)), row.shape)
        total += float(row[piece, end])
        done[piece] = True
        here = 2 * int(piece) + (1 - int(end))  # left at the other end
    return total
