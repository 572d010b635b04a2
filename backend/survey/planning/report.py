"""Flight time of a lane plan, and the grid angle that minimises it.

Time = path length / cruise speed, plus, at each corner where the vehicle turns sharply
(the two ends of each turnaround leg, or each photo when hovering), the time lost braking
to a stop and speeding up again: with acceleration a, covering the braking and speeding-up
distances v²/a at mean speed v/2 takes v/a longer than at cruise speed.
"""

from __future__ import annotations

import math

from shapely.geometry import Polygon

from backend.survey.planning.bound import lower_bound
from backend.survey.planning.camera import CameraCalc
from backend.survey.planning.lanes import LanePlan
from backend.survey.planning.planner import plan_lanes

DEFAULT_ACCEL_MS2 = 2.5  # ArduCopter's WPNAV_ACCEL default, 250 cm/s²


def flight_time_s(
    plan: LanePlan,
    speed_ms: float,
    accel_ms2: float = DEFAULT_ACCEL_MS2,
    *,
    hover_s_per_photo: float | None = None,
) -> float:
    corners = 2 * max(len(plan.lanes) - 1, 0) + 2
    time = plan.path_length_m / speed_ms + corners * speed_ms / accel_ms2
    if hover_s_per_photo is not None:
        time += plan.photo_count * (speed_ms / accel_ms2 + hover_s_per_photo)
    return time


def best_angle(
    area: Polygon,
    calc: CameraCalc,
    speed_ms: float,
    *,
    turnaround_m: float,
    step_deg: float = 5.0,
) -> float:
    """The grid angle (0 to 180, every `step_deg`) giving the shortest flight time, turns
    included: the same angle as planning every one, found by branch and bound. Each angle's
    time is bounded from below from its rows alone (bound.lower_bound, quick: the least
    lanes, turnarounds and transits, and the plan's corners, one lane per piece); the angles
    are planned in the order of that bound, and the search stops at the first whose bound
    is above the best time planned so far."""
    angles = [i * step_deg for i in range(math.ceil(180.0 / step_deg - 1e-9))]
    floors = []
    for angle in angles:
        bound = lower_bound(area, calc, angle, turnaround_m, quick=True)
        corners = 2 * max(bound.lanes - 1, 0) + 2
        floors.append(bound.total_m / speed_ms + corners * speed_ms / DEFAULT_ACCEL_MS2)
    best: tuple[float, float] | None = None
    for floor, angle in sorted(zip(floors, angles, strict=True)):
        if best is not None and floor * (1 - 1e-9) > best[0]:
            break
        plan = plan_lanes(area, calc, angle_deg=angle, turnaround_m=turnaround_m)
        candidate = (flight_time_s(plan, speed_ms), angle)
        if best is None or candidate < best:
            best = candidate
    assert best is not None
    return best[1]
