"""Flight time of a lane plan, and the grid angle that minimises it.

Time = path length / cruise speed, plus, at each corner where the vehicle turns sharply
(the two ends of each turnaround leg, or each photo when hovering), the time lost braking
to a stop and speeding up again: with acceleration a, covering the braking and speeding-up
distances v²/a at mean speed v/2 takes v/a longer than at cruise speed.
"""

from __future__ import annotations

from shapely.geometry import Polygon

from backend.missions.survey.camera import CameraCalc
from backend.missions.survey.planner import LanePlan, plan_lanes

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
    """The grid angle (0 to 180) giving the shortest flight time, turns included."""
    best: tuple[float, float] | None = None
    angle = 0.0
    while angle < 180.0:
        plan = plan_lanes(area, calc, angle_deg=angle, turnaround_m=turnaround_m)
        t = flight_time_s(plan, speed_ms)
        if best is None or t < best[0]:
            best = (t, angle)
        angle += step_deg
    assert best is not None
    return best[1]
