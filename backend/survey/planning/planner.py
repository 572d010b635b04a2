"""The lane planner: boustrophedon lanes over a polygon in a local metric frame.

Works on shapely 2 geometry in metres (east, north) of a tangent plane at the area's centre
(common.geodesy.LocalFrame), so an area across a UTM zone boundary, or the antimeridian,
needs nothing special.

Lanes run along the grid angle. Each lane covers a strip one lane spacing wide; its ends
are half a trigger distance inside where the area's part of that strip begins and ends (not
where the centre line meets the border), so a slanted edge is still covered and the photos'
footprints at the requested overlaps just reach it. A lane is split where it would cross a
hole (a no-fly area), and ends a turnaround short of it. backend/survey/planning/bound.py
gives the least path any lane plan on these rows can fly; the planner's is held to at most
1.05 times it (tests/unit/survey/planning/test_planner.py).
Lanes are grouped into cells (boustrophedon decomposition: a cell goes on while each row
has exactly one segment overlapping the one before), each cell is flown back and forth,
and the cells are chained nearest first, so a concave area is not crossed by long detours;
then the lanes' order and directions are improved one move at a time (sequence.py). A
straight transit into a hole is dearer than any path to both, so it is flown only where no
order avoids it. Photos are taken at each lane's entry, every trigger distance, and at its
exit, as QGC's survey has ArduPilot take them; each lane gets a turnaround (outside the
area) at both ends.
"""

from __future__ import annotations

import math

import numpy as np
import shapely
from shapely import affinity
from shapely.geometry import LineString, Polygon
from shapely.geometry.base import BaseGeometry
from shapely.validation import explain_validity

from backend.survey.planning.camera import CameraCalc
from backend.survey.planning.holes import crossings
from backend.survey.planning.lanes import Grid, Lane, LanePlan, Point
from backend.survey.planning.sequence import Step, improve

MAX_VERTICES = 10_000
DEFAULT_TURNAROUND_M = 10.0  # QGC's default for multirotors


class PlanError(ValueError):
    """An area or setting no survey can be planned for; the message says what to change."""


def validate_area(area: Polygon) -> Polygon:
    """The area as a valid polygon, or a PlanError saying what is wrong with it."""
    if not isinstance(area, Polygon):
        raise PlanError("the area must be one polygon")
    vertices = len(area.exterior.coords) + sum(len(r.coords) for r in area.interiors)
    if vertices > MAX_VERTICES:
        raise PlanError(f"the area has {vertices} vertices; at most {MAX_VERTICES} are allowed")
    if len(area.exterior.coords) < 4:
        raise PlanError("the area needs at least 3 distinct corners")
    outline = Polygon(area.exterior)
    holes = [Polygon(ring) for ring in area.interiors]
    if (
        holes
        and outline.is_valid
        and all(h.is_valid for h in holes)
        and outline.difference(shapely.union_all(holes)).area <= 1e-9 * max(outline.area, 1.0)
    ):
        raise PlanError("the holes cover the whole area; leave some of it to survey")
    if not area.is_valid:
        # e.g. "Self-intersection[12.5 40.1]": where it crosses, in the caller's frame.
        raise PlanError(f"the area is not a valid polygon: {explain_validity(area)}")
    if area.area <= 0:
        raise PlanError("the area is empty (its holes cover it all, or it has no extent)")
    return area


Piece = tuple[float, float, float]  # a row's piece of the area: x from a to b at y, rotated


def hole_margin_m(trigger_m: float, turnaround_m: float) -> float:
    """How far short of a hole a lane's piece ends: its turnaround leg may not enter the
    hole, and the lane's last photo covers half a trigger distance past its end."""
    return max(0.0, turnaround_m - trigger_m / 2)


def rotated_area(area: Polygon, angle_deg: float) -> Polygon:
    """The area in the frame plan_lanes lays rows in: rotated by -angle about its centroid."""
    area = validate_area(area)
    centre = area.centroid
    rotated = affinity.rotate(area, -angle_deg, origin=(centre.x, centre.y))
    assert isinstance(rotated, Polygon)
    return rotated


def row_pieces(
    area: Polygon, spacing_m: float, angle_deg: float, hole_margin: float = 0.0
) -> list[Piece]:
    """The pieces plan_lanes flies, in the frame rotated by -angle about the area's centroid:
    per row from south to north, each lane's extent before it is cut to its photos."""
    rotated = rotated_area(area, angle_deg)
    _, miny, _, maxy = rotated.bounds
    ys = _rows(miny, maxy, spacing_m, None)
    rows = _segments(rotated, spacing_m, ys, hole_margin)
    return [(a, b, y) for row, y in zip(rows, ys, strict=True) for a, b in row]


def _rows(miny: float, maxy: float, spacing: float, grid_y: float | None) -> list[float]:
    """The lanes' y, each covering a strip one spacing wide: centred on the area, or on a
    fleet's common grid so that parts' lanes line up."""
    if grid_y is None:
        rows = max(1, math.ceil((maxy - miny) / spacing - 1e-9))
        y0 = (miny + maxy) / 2 - (rows - 1) * spacing / 2
        return [y0 + i * spacing for i in range(rows)]
    first = math.floor((miny - grid_y) / spacing + 0.5 + 1e-6)
    last = max(first, math.ceil((maxy - grid_y) / spacing - 0.5 - 1e-6))
    return [grid_y + k * spacing for k in range(first, last + 1)]


def _segments(
    area: Polygon, spacing: float, ys: list[float], hole_margin: float = 0.0
) -> list[list[tuple[float, float]]]:
    """Per row (from south to north in the rotated frame), the lanes' x extents, cut
    `hole_margin` short of where a hole meets the strip."""
    minx, _, maxx, _ = area.bounds
    # GEOS's rectangle clipping: the same pieces as an overlay with each strip, in half the
    # time (its output may be invalid, but only the parts' bounds are used).
    pieces = [
        shapely.clip_by_rect(area, minx - 1, y - spacing / 2, maxx + 1, y + spacing / 2) for y in ys
    ]
    holes = [Polygon(ring) for ring in area.interiors]
    hole_boxes = [hole.bounds for hole in holes]
    out: list[list[tuple[float, float]]] = []
    for y, piece in zip(ys, pieces, strict=True):
        parts = [
            p for p in getattr(piece, "geoms", [piece]) if isinstance(p, Polygon) and p.area > 1e-6
        ]
        row: list[tuple[float, float]] = []
        for part in parts:
            x0, _, x1, _ = part.bounds
            extents = [(x0, x1)]
            for hole, (bx0, by0, bx1, by1) in zip(holes, hole_boxes, strict=True):
                if not (by0 <= y <= by1 and bx0 <= x1 and x0 <= bx1):
                    continue  # the hole's box misses the lane: it cannot cross it
                if hole.intersects(LineString([(x0, y), (x1, y)])):
                    # No lane crosses a hole: cut the lane where the hole meets its strip.
                    hx0, _, hx1, _ = hole.intersection(part.envelope).bounds
                    hx0, hx1 = hx0 - hole_margin, hx1 + hole_margin
                    extents = [
                        seg
                        for a, b in extents
                        for seg in ((a, min(b, hx0)), (max(a, hx1), b))
                        if seg[1] - seg[0] > 1e-6
                    ]
            row.extend(extents)
        out.append(sorted(row))
    return out


def _cells(rows: list[list[tuple[float, float]]]) -> list[list[tuple[int, float, float]]]:
    """Boustrophedon cells: runs of rows where one segment continues exactly one other."""
    cells: list[list[tuple[int, float, float]]] = []
    open_cells: dict[tuple[float, float], int] = {}
    prev: list[tuple[float, float]] = []
    for r, row in enumerate(rows):
        nxt: dict[tuple[float, float], int] = {}
        for seg in row:
            above = [p for p in prev if p[0] < seg[1] and seg[0] < p[1]]
            below = [s for s in row if above and s[0] < above[0][1] and above[0][0] < s[1]]
            if len(above) == 1 and len(below) == 1 and above[0] in open_cells:
                idx = open_cells[above[0]]
                # A cell also ends when the next row's segment of another cell would need it.
                others = [p for p in rows[r - 1] if p[0] < seg[1] and seg[0] < p[1]]
                if len(others) == 1:
                    cells[idx].append((r, *seg))
                    nxt[seg] = idx
                    continue
            cells.append([(r, *seg)])
            nxt[seg] = len(cells) - 1
        open_cells = nxt
        prev = row
    return cells


Cell = list[tuple[int, float, float]]
Visit = tuple[int, bool, bool]  # cell, flown from its last row, first lane westward
_MULTI_START_CELLS = 30  # above this, one greedy chain from the nearest cell
_RESTARTS_LANES = 640  # around holes, the lane search restarts 8 times, fewer past 80 lanes


def _ends(cell: Cell, ys: list[float], rev_rows: bool, rev_x: bool) -> tuple[Point, Point, float]:
    """Where flying `cell` this way starts and ends (rotated frame), and its transit from
    each lane's end to the next one's start: a cell whose rows shrink costs a detour at the
    step flown one way, none flown the other."""
    rows = list(reversed(cell)) if rev_rows else cell
    transit = 0.0
    prev_end: float | None = None
    for k, (_, a, b) in enumerate(rows):
        forward = (k % 2 == 0) != rev_x
        start, end = (a, b) if forward else (b, a)
        if prev_end is not None:
            transit += abs(start - prev_end)
        prev_end = end
    r0, a0, b0 = rows[0]
    r1, a1, b1 = rows[-1]
    last_forward = ((len(rows) - 1) % 2 == 0) != rev_x
    return (b0 if rev_x else a0, ys[r0]), (b1 if last_forward else a1, ys[r1]), transit


def _order(
    cells: list[Cell], ys: list[float], origin: Point | None, holes: BaseGeometry
) -> list[Visit]:
    """The order and direction to fly the cells in: from each possible first cell and
    corner, the nearest next cell each time; the chain with the least transit wins. A
    transit into a hole costs more than any chain, so one is taken only if none avoids it."""
    ways = [(i, rr, rx) for i in range(len(cells)) for rr in (False, True) for rx in (False, True)]
    ends = {w: _ends(cells[w[0]], ys, w[1], w[2]) for w in ways}
    index = {w: k for k, w in enumerate(ways)}
    penalty = np.zeros((len(ways), len(ways)))
    if not holes.is_empty and len(cells) > 1:
        exits = np.array([ends[w][1] for w in ways])
        entries = np.array([ends[w][0] for w in ways])
        width = float(np.ptp(np.concatenate([exits, entries]), axis=0).sum()) + 1.0
        penalty = crossings(exits, entries, holes) * width * (len(cells) + 1)

    def chain(first: Visit) -> tuple[float, list[Visit]]:
        cost = math.dist(origin, ends[first][0]) if origin is not None else 0.0
        cost += ends[first][2]
        order, done, here = [first], {first[0]}, first
        while len(done) < len(cells):
            step, way = min(
                (
                    math.dist(ends[here][1], ends[w][0])
                    + ends[w][2]
                    + penalty[index[here], index[w]],
                    w,
                )
                for w in ways
                if w[0] not in done
            )
            cost += step
            order.append(way)
            done.add(way[0])
            here = way
        return cost, order

    if origin is not None and len(cells) > _MULTI_START_CELLS:
        firsts = [min(ways, key=lambda w: math.dist(origin, ends[w][0]))]
    elif len(cells) > _MULTI_START_CELLS:
        firsts = [ways[0]]
    else:
        firsts = ways
    return min((chain(first) for first in firsts), key=lambda c: c[0])[1]


def plan_lanes(
    area: Polygon,
    calc: CameraCalc,
    *,
    angle_deg: float = 0.0,
    turnaround_m: float = DEFAULT_TURNAROUND_M,
    start: tuple[float, float] | None = None,
    whole_area: bool = True,
    grid: Grid | None = None,
) -> LanePlan:
    """Lanes over `area` (metres) at `angle_deg` (the lanes' heading, degrees east of north's
    perpendicular: 0 runs them east-west). With a `grid`, lanes and photos lie on that
    common grid (a fleet's parts), else the lanes are centred on the area."""
    area = validate_area(area)
    spacing, trigger = calc.lane_spacing_m, calc.trigger_distance_m
    # A fleet's part may be smaller than a photo; the area as a whole may not.
    if whole_area and area.area < calc.footprint_side_m * calc.footprint_frontal_m:
        raise PlanError(
            f"the area ({area.area:.0f} m²) is smaller than one photo's footprint "
            f"({calc.footprint_side_m:.0f} x {calc.footprint_frontal_m:.0f} m); "
            "draw a larger area or fly lower"
        )
    cx, cy = (grid.cx, grid.cy) if grid else (area.centroid.x, area.centroid.y)
    rotated = affinity.rotate(area, -angle_deg, origin=(cx, cy))
    assert isinstance(rotated, Polygon)
    _, miny, _, maxy = rotated.bounds
    ys = _rows(miny, maxy, spacing, grid.y0 if grid else None)
    rows = _segments(rotated, spacing, ys, hole_margin_m(trigger, turnaround_m))
    cos_a, sin_a = math.cos(math.radians(angle_deg)), math.sin(math.radians(angle_deg))

    def back(x: float, y: float) -> tuple[float, float]:
        dx, dy = x - cx, y - cy
        return (cx + dx * cos_a - dy * sin_a, cy + dx * sin_a + dy * cos_a)

    holes = shapely.union_all([Polygon(ring) for ring in rotated.interiors])
    cells = _cells(rows)
    origin = None
    if start is not None:
        # where the vehicle is, in the rotated frame
        dx, dy = start[0] - cx, start[1] - cy
        origin = (cx + dx * cos_a + dy * sin_a, cy - dx * sin_a + dy * cos_a)
    keep_out = None if holes.is_empty else holes.buffer(-0.01)
    runs: list[tuple[float, float, float, int]] = []  # y, from x, to x, photos
    steps: list[Step] = []
    for i, rev_rows, rev_x in _order(cells, ys, origin, holes):
        cell = cells[i]
        for k, (r, a, b) in enumerate(reversed(cell) if rev_rows else cell):
            if grid is not None and holes.is_empty:
                # Photos on the common grid: the first within half a trigger distance
                # past the start, the last within half one before the end.
                a = grid.x0 + math.floor((a - grid.x0) / trigger + 0.5 + 1e-6) * trigger
                b = max(a, grid.x0 + math.ceil((b - grid.x0) / trigger - 0.5 - 1e-6) * trigger)
                shots = round((b - a) / trigger)
            else:
                # A photo's footprint at the requested overlaps reaches half a trigger
                # distance along the lane, so the lane starts and ends half a trigger
                # distance inside the piece (a piece shorter than that gets its photos at
                # its middle): no plan on this row can fly less (bound.py).
                if b - a > trigger:
                    a, b = a + trigger / 2, b - trigger / 2
                else:
                    a = b = _point_lane(a, b, ys[r], trigger, turnaround_m, keep_out)
                # As QGC and ArduPilot fly it: a photo at the entry (DO_SET_CAM_TRIGG_DIST
                # with "trigger once"), one per trigger distance, and one at the exit (the
                # stop command triggers once too).
                shots = max(1, math.ceil((b - a) / trigger - 1e-9))
            forward = (k % 2 == 0) != rev_x
            steps.append((len(runs), 0 if forward else 1))
            runs.append((ys[r], a, b, shots))
    turns = np.array(
        [[(a - turnaround_m, y), (b + turnaround_m, y)] for y, a, b, _ in runs]
    ).reshape(-1, 2, 2)
    points = turns.reshape(-1, 2)
    blocked = None if holes.is_empty else crossings(points, points, holes)
    lanes: list[Lane] = []
    path: list[tuple[float, float]] = []
    for index, end in improve(
        steps,
        turns,
        origin,
        blocked,
        restarts=0 if blocked is None else min(8, max(1, _RESTARTS_LANES // len(runs))),
    ):
        y, a, b, shots = runs[index]
        forward = end == 0
        xs, xe = (a, b) if forward else (b, a)
        step = trigger if forward else -trigger
        along = [xs + j * step for j in range(shots)]
        photos = tuple(back(x, y) for x in [*along, xe])
        turn = turnaround_m if forward else -turnaround_m
        lane = Lane(back(xs, y), back(xe, y), photos)
        lanes.append(lane)
        path.extend([back(xs - turn, y), lane.start, lane.end, back(xe + turn, y)])
    return LanePlan(
        lanes=tuple(lanes),
        path=tuple(path),
        angle_deg=angle_deg,
        lane_spacing_m=spacing,
        trigger_distance_m=trigger,
        turnaround_m=turnaround_m,
    )


def _point_lane(
    a: float, b: float, y: float, trigger: float, turnaround_m: float, keep_out: BaseGeometry | None
) -> float:
    """Where to take the photos of a piece shorter than a trigger distance: anywhere from
    b - t/2 to a + t/2 covers it; the middle, unless a turnaround from there would enter a
    hole, then the end of that span away from the hole."""
    middle = (a + b) / 2
    if keep_out is None:
        return middle
    for x in (middle, b - trigger / 2, a + trigger / 2):
        legs = LineString([(x - turnaround_m, y), (x + turnaround_m, y)])
        if not legs.intersects(keep_out):
            return x
    return middle
