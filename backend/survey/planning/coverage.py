"""What a lane plan's photos cover: each photo's footprint, their union lane by lane, and
the share of the area they see, at the footprints and at the requested overlaps."""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
import shapely
from shapely.geometry import Polygon

from backend.survey.planning.camera import CameraCalc
from backend.survey.planning.lanes import LanePlan


def _rectangles(
    centres: np.ndarray, along_m: np.ndarray | float, across_m: float, angle_deg: float
) -> np.ndarray:
    """Rectangles `along_m` long in the lanes' direction and `across_m` wide, one per centre
    (an (n, 2) array), as an array of polygons built in one call."""
    u = np.array([math.cos(math.radians(angle_deg)), math.sin(math.radians(angle_deg))])
    v = np.array([-u[1], u[0]])
    half_along = np.broadcast_to(np.asarray(along_m, dtype=float) / 2, (len(centres),))
    corners = [(-1, -1), (1, -1), (1, 1), (-1, 1), (-1, -1)]
    coords = np.stack(
        [centres + (i * half_along)[:, None] * u + (j * across_m / 2) * v for i, j in corners],
        axis=1,
    )
    return np.asarray(shapely.polygons(coords))


def footprints(plan: LanePlan, side_m: float, frontal_m: float) -> list[Polygon]:
    """Each photo's footprint (nadir, camera across the lanes), `side_m` x `frontal_m`."""
    # the plan's angle, not each lane's own heading: a lane may be a single point
    photos = np.array([p for lane in plan.lanes for p in lane.photos], dtype=float).reshape(-1, 2)
    return list(_rectangles(photos, frontal_m, side_m, plan.angle_deg))


def swaths(plan: LanePlan, side_m: float, frontal_m: float) -> list[Polygon]:
    """The union of the photos' footprints, lane by lane: a lane's photos lie on one line
    and their footprints share that axis and width, so a run of photos at most one
    footprint length apart covers exactly the rectangle from the first one's footprint to
    the last one's. A few rectangles per lane instead of one per photo make the coverage
    check a union of lanes, not of thousands of photos."""
    u = np.array([math.cos(math.radians(plan.angle_deg)), math.sin(math.radians(plan.angle_deg))])
    v = np.array([-u[1], u[0]])
    centres, lengths = [], []
    for lane in plan.lanes:
        photos = np.asarray(lane.photos, dtype=float).reshape(-1, 2)
        if not len(photos):
            continue
        along = np.sort(photos @ u)
        across = float(np.mean(photos @ v))
        breaks = np.flatnonzero(np.diff(along) > frontal_m) + 1
        for run in np.split(along, breaks):
            lo, hi = float(run[0]) - frontal_m / 2, float(run[-1]) + frontal_m / 2
            centres.append((lo + hi) / 2 * u + across * v)
            lengths.append(hi - lo)
    if not centres:
        return []
    return list(_rectangles(np.array(centres), np.array(lengths), side_m, plan.angle_deg))


def covered_fraction(area: Polygon, shapes: Sequence[Polygon]) -> float:
    """The share of `area` (holes excluded) that the union of `shapes` covers."""
    union = shapely.union_all(shapes)
    return float(area.intersection(union).area) / float(area.area)


def coverage(plan: LanePlan, area: Polygon, calc: CameraCalc) -> tuple[float, float]:
    """(footprint coverage, coverage at the requested overlaps), each 0..1, from the photos.

    The second uses each photo's footprint shrunk to one lane spacing by one trigger
    distance: if those cover a point, the real footprints around it overlap by at least the
    requested side and front overlaps. Both union the footprints lane by lane (swaths).
    """
    real = swaths(plan, calc.footprint_side_m, calc.footprint_frontal_m)
    adjusted = swaths(plan, calc.lane_spacing_m * 1.0001, calc.trigger_distance_m * 1.0001)
    return covered_fraction(area, real), covered_fraction(area, adjusted)
