"""The fleet split: one area cut into non-overlapping parts, one per drone, balanced on each
drone's whole time: the transit from where it is to its part, the part, and the way home.

The parts share one lane and photo grid, and the cuts run across the lanes as staircases
on that grid, so every part keeps the lane direction and a part's time grows by about one
trigger distance's flight per step of its cut: drones are taken in order along the lanes
by where they are, for a target time T each drone's cut is found by bisection so its time
reaches T, and T itself is found by bisection until the last drone's part also takes T.
The slowest drone's time ends within a few percent of the mean (checked by
tests/unit/survey/planning/test_split.py: at most 1.05 x).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import shapely
from shapely import affinity
from shapely.geometry import Polygon, box
from shapely.geometry.base import BaseGeometry

from backend.survey.planning.camera import CameraCalc
from backend.survey.planning.lanes import Grid, Lane, LanePlan
from backend.survey.planning.planner import (
    DEFAULT_TURNAROUND_M,
    PlanError,
    plan_lanes,
    validate_area,
)
from backend.survey.planning.report import DEFAULT_ACCEL_MS2, flight_time_s

_MIN_PIECE_M2 = 1.0  # slivers a cut leaves along an edge are flown by the neighbour


@dataclass(frozen=True, slots=True)
class Drone:
    """Where a drone is and where it goes home to, in the area's local frame (metres)."""

    name: str
    position: tuple[float, float]
    home: tuple[float, float]
    speed_ms: float = 10.0


@dataclass(frozen=True, slots=True)
class Part:
    drone: Drone
    area: BaseGeometry  # Polygon or MultiPolygon
    plan: LanePlan
    transit_s: float
    survey_s: float
    home_s: float

    @property
    def total_s(self) -> float:
        return self.transit_s + self.survey_s + self.home_s


def _pieces(geom: BaseGeometry) -> list[Polygon]:
    polys = [g for g in getattr(geom, "geoms", [geom]) if isinstance(g, Polygon)]
    return [p for p in polys if p.area >= _MIN_PIECE_M2]


def plan_part(
    geom: BaseGeometry,
    calc: CameraCalc,
    angle_deg: float,
    turnaround_m: float,
    start: tuple[float, float],
    grid: Grid | None = None,
) -> LanePlan:
    """One plan over every piece of a part, each piece started from the last one's end."""
    lanes: list[Lane] = []
    path: list[tuple[float, float]] = []
    here = start
    pieces = _pieces(geom)
    while pieces:
        pieces.sort(key=lambda p: p.distance(shapely.Point(here)))
        piece = pieces.pop(0)
        plan = plan_lanes(
            piece,
            calc,
            angle_deg=angle_deg,
            turnaround_m=turnaround_m,
            start=here,
            whole_area=False,
        )
        lanes.extend(plan.lanes)
        path.extend(plan.path)
        here = path[-1] if path else here
    return LanePlan(
        lanes=tuple(lanes),
        path=tuple(path),
        angle_deg=angle_deg,
        lane_spacing_m=calc.lane_spacing_m,
        trigger_distance_m=calc.trigger_distance_m,
        turnaround_m=turnaround_m,
    )


def _part(
    drone: Drone,
    geom: BaseGeometry,
    calc: CameraCalc,
    angle_deg: float,
    turnaround_m: float,
    accel_ms2: float,
    grid: Grid,
) -> Part:
    plan = plan_part(geom, calc, angle_deg, turnaround_m, drone.position, grid)
    if not plan.path:
        return Part(
            drone, geom, plan, 0.0, 0.0, math.dist(drone.position, drone.home) / drone.speed_ms
        )
    return Part(
        drone=drone,
        area=geom,
        plan=plan,
        transit_s=math.dist(drone.position, plan.path[0]) / drone.speed_ms,
        survey_s=flight_time_s(plan, drone.speed_ms, accel_ms2),
        home_s=math.dist(plan.path[-1], drone.home) / drone.speed_ms,
    )


def split(
    area: Polygon,
    calc: CameraCalc,
    drones: Sequence[Drone],
    *,
    angle_deg: float = 0.0,
    turnaround_m: float = DEFAULT_TURNAROUND_M,
    accel_ms2: float = DEFAULT_ACCEL_MS2,
    tolerance: float = 0.002,
) -> list[Part]:
    """One part per drone, in the order of `drones`; their union is the area."""
    area = validate_area(area)
    if not drones:
        raise PlanError("choose at least one drone")
    if len({d.name for d in drones}) != len(drones):
        raise PlanError("each drone may be chosen once")
    spacing, trigger = calc.lane_spacing_m, calc.trigger_distance_m
    centre = area.centroid
    rotated = affinity.rotate(area, -angle_deg, origin=centre)
    minx, miny, maxx, maxy = rotated.bounds
    n_rows = max(1, math.ceil((maxy - miny) / spacing - 1e-9))
    y0 = (miny + maxy) / 2 - (n_rows - 1) * spacing / 2
    grid = Grid(centre.x, centre.y, minx, y0)
    n_cols = max(1, math.ceil((maxx - minx) / trigger))
    # A cut is a staircase on the grid: cut u puts row r's boundary at column u // n_rows,
    # one column further for the first u % n_rows rows, so each step of u moves one lane's
    # end by one trigger distance and the parts' times can be balanced finely.
    u_max = n_cols * n_rows
    bands = [
        (
            miny - 1 if r == 0 else y0 + (r - 0.5) * spacing,
            maxy + 1 if r == n_rows - 1 else y0 + (r + 0.5) * spacing,
        )
        for r in range(n_rows)
    ]

    def col_x(u: int, r: int) -> float:
        if u >= u_max:
            return maxx + 1
        col = u // n_rows + (1 if r < u % n_rows else 0)
        return minx + col * trigger if u > 0 else minx - 1

    def part_area(u0: int, u1: int) -> BaseGeometry:
        boxes = [
            box(col_x(u0, r), lo, col_x(u1, r), hi)
            for r, (lo, hi) in enumerate(bands)
            if col_x(u1, r) > col_x(u0, r)
        ]
        cut = rotated.intersection(shapely.union_all(boxes))
        return affinity.rotate(cut, angle_deg, origin=centre)

    def along(d: Drone) -> float:
        return float(affinity.rotate(shapely.Point(d.position), -angle_deg, origin=centre).x)

    order = sorted(drones, key=along)

    def make(d: Drone, u0: int, u1: int) -> Part:
        return _part(d, part_area(u0, u1), calc, angle_deg, turnaround_m, accel_ms2, grid)

    def cuts_for(target: float) -> tuple[list[int], float]:
        """Cuts giving each drone but the last at least `target`; the last one's time."""
        cuts = [0]
        for d in order[:-1]:
            lo, hi = cuts[-1], u_max
            if make(d, lo, hi).total_s <= target:
                cuts.append(u_max)
                continue
            while hi - lo > 1:
                mid = (lo + hi) // 2
                if make(d, cuts[-1], mid).total_s < target:
                    lo = mid
                else:
                    hi = mid
            cuts.append(hi)
        return cuts, make(order[-1], cuts[-1], u_max).total_s

    def parts_for(cuts: list[int]) -> list[Part]:
        bounds = [*cuts, u_max]
        return [make(d, bounds[i], bounds[i + 1]) for i, d in enumerate(order)]

    if len(order) == 1:
        best = parts_for([0])
    else:
        lo, hi = (
            0.0,
            make(order[0], 0, u_max).total_s
            + max(math.dist(d.position, d.home) / d.speed_ms for d in order),
        )
        best, best_max = [], math.inf
        for _ in range(40):
            target = (lo + hi) / 2
            cuts, last = cuts_for(target)
            candidate = parts_for(cuts)
            slowest = max(p.total_s for p in candidate)
            if slowest < best_max:
                best, best_max = candidate, slowest
            if last > target:
                lo = target
            else:
                hi = target
            if hi - lo < tolerance * hi:
                break
    by_name = {p.drone.name: p for p in best}
    return [by_name[d.name] for d in drones]
