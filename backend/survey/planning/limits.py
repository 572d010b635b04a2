"""How big a survey plan will be, from arithmetic alone, before anything is planned.

Planning costs time and memory in proportion to its lanes and photos: a 4.4 km square at
1 m would have about 10,000 lanes and 220 million photos, which no hub can plan (nor any
drone fly). So the plan is estimated first, from the area's size and extent and the
camera's lane spacing and trigger distance, and refused past the hub's limits with the
estimate and the limit's setting named; the estimates are what the planner will at least
make (a lane per row, a photo per trigger distance), so nothing that fits is refused:

- lanes: rows one lane spacing apart across the area, at the requested grid angle, or at
  the angle (every 5°, as report.best_angle tries them) with the fewest;
- photos: the area over the ground one photo stands for (lane spacing x trigger distance),
  plus the photo each lane takes at its exit;
- items per drone: each lane's six items (turnaround, entry, trigger on, exit, trigger off,
  turnaround; per photo, a waypoint and a shutter item each instead), plus take-off, speed
  and RTL. The fleet split shares the lanes out, so the busiest drone has at least its
  share; the exact count is checked again on the planned missions (`check_missions`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from shapely.geometry import Polygon

from backend.survey.planning.camera import CameraCalc
from backend.survey.planning.planner import PlanError

ANGLE_STEP_DEG = 5.0  # report.best_angle's step
_FIXED_ITEMS = 3  # take-off, DO_CHANGE_SPEED, RTL
_ITEMS_PER_LANE = 6
_ITEMS_PER_LANE_PER_PHOTO = 2  # its two turnarounds; each photo adds two more


class PlanTooLarge(PlanError):
    """A plan over one of the hub's limits; the message names the estimate, the limit
    and its setting."""


@dataclass(frozen=True, slots=True)
class SurveyLimits:
    """The hub's settings of the same names (backend/settings/surveys.py)."""

    survey_max_lanes: int
    survey_max_photos: int
    survey_max_mission_items: int


@dataclass(frozen=True, slots=True)
class Estimate:
    lanes: int
    photos: int
    items_per_drone: int  # the least the busiest drone's mission has


def fewest_rows(area: Polygon, spacing_m: float, angle_deg: float | None) -> int:
    """Rows across the area at `angle_deg`, or at the candidate angle with the fewest."""
    points = np.asarray(area.exterior.coords)
    angles = (
        np.array([angle_deg]) if angle_deg is not None else np.arange(0.0, 180.0, ANGLE_STEP_DEG)
    )
    radians = np.radians(angles)
    # Rows stack across the lanes: along (-sin a, cos a) for lanes heading a from east.
    across = points @ np.stack([-np.sin(radians), np.cos(radians)])
    widths = across.max(axis=0) - across.min(axis=0)
    return max(1, math.ceil(float(widths.min()) / spacing_m - 1e-9))


def estimate(
    area: Polygon, calc: CameraCalc, *, drones: int, angle_deg: float | None, per_photo: bool
) -> Estimate:
    lanes = fewest_rows(area, calc.lane_spacing_m, angle_deg)
    per_photo_area = calc.lane_spacing_m * calc.trigger_distance_m
    photos = math.ceil(float(area.area) / per_photo_area) + lanes
    lanes_each, photos_each = math.ceil(lanes / drones), math.ceil(photos / drones)
    if per_photo:
        items = _ITEMS_PER_LANE_PER_PHOTO * (lanes_each + photos_each)
    else:
        items = _ITEMS_PER_LANE * lanes_each
    return Estimate(lanes=lanes, photos=photos, items_per_drone=items + _FIXED_ITEMS)


def check_estimate(found: Estimate, limits: SurveyLimits) -> None:
    """PlanTooLarge naming every limit the estimate is over."""
    over = [
        f"about {value:,} {what}; the limit is {limit:,} ({setting})"
        for value, what, limit, setting in (
            (found.lanes, "lanes", limits.survey_max_lanes, "survey_max_lanes"),
            (found.photos, "photos", limits.survey_max_photos, "survey_max_photos"),
            (
                found.items_per_drone,
                "mission items for a drone",
                limits.survey_max_mission_items,
                "survey_max_mission_items",
            ),
        )
        if value > limit
    ]
    if over:
        raise PlanTooLarge(
            f"the plan would need {'; and '.join(over)}. Fly higher, lower the overlaps "
            "or survey a smaller area"
        )


def check_missions(missions: dict[str, int], limits: SurveyLimits) -> None:
    """PlanTooLarge if a drone's planned mission (its item count) is over the mission
    store limit: it could not be uploaded."""
    limit = limits.survey_max_mission_items
    over = {vid: count for vid, count in missions.items() if count > limit}
    if over:
        listed = ", ".join(f"{vid} {count:,}" for vid, count in over.items())
        raise PlanTooLarge(
            f"a drone's mission would have more items than it can store (items: {listed}); "
            f"the limit is {limit:,} (survey_max_mission_items). Fly higher, lower the side "
            "overlap or survey a smaller area (the drones share out each lane, so more drones "
            "do not make a mission shorter)"
        )
