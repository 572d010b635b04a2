"""Survey planning benchmark: planning time for square-ish areas of 0.1, 1 and 10 km²
(the bar is 1 km² in at most 1 s), the path length against its lower bound, and the
fleet split's time for 2 to 16 drones over 1 km² with the slowest drone's time / mean.

    .venv/bin/python bench/bench_survey.py

"plan" is one lane plan at a given angle; "auto angle" searches the angle every 5°;
"coverage" is the footprint coverage check. "strip bound" is planner.strip_bound_m (what
any plan at that spacing and angle must fly; the bar is 1.05), "area bound" the looser
area / spacing one. Each time is the best of 3 runs. Prints a Markdown table; asserts
nothing.
"""

from __future__ import annotations

import math
import sys
import time
from collections.abc import Callable
from functools import partial
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from shapely.geometry import Polygon

from backend.missions.survey.camera import calculate, preset
from backend.missions.survey.planner import coverage, lower_bound_m, plan_lanes, strip_bound_m
from backend.missions.survey.report import best_angle
from backend.missions.survey.split import Drone, split

CALC = calculate(preset("sony_a6000_16mm"), gsd_cm=2.0, side_overlap_pct=70, front_overlap_pct=80)


def _best_s(call: Callable[[], object]) -> float:
    best = math.inf
    for _ in range(3):
        t = time.perf_counter()
        call()
        best = min(best, time.perf_counter() - t)
    return best


def _area(km2: float) -> Polygon:
    # A slanted quadrilateral, so lanes meet its edges at an angle.
    s = math.sqrt(km2) * 1000
    return Polygon([(0, 0), (s, 0.1 * s), (1.05 * s, s), (-0.05 * s, 0.95 * s)])


def main() -> None:
    print(f"camera {CALC.camera.name}, GSD {CALC.gsd_cm} cm, spacing {CALC.lane_spacing_m:.1f} m")
    print(
        "| area km² | lanes | photos | plan s | auto angle s | coverage s | covered % "
        "| path / strip bound | path / area bound |"
    )
    print("|---|---|---|---|---|---|---|---|---|")
    for km2 in (0.1, 1.0, 10.0):
        area = _area(km2)
        plan = plan_lanes(area, CALC, angle_deg=0)
        rows = math.ceil((area.bounds[3] - area.bounds[1]) / CALC.lane_spacing_m - 1e-9)
        ratio = plan.path_length_m / lower_bound_m(
            area, CALC.lane_spacing_m, plan.turnaround_m, rows
        )
        strip = plan.path_length_m / strip_bound_m(area, CALC, 0.0, plan.turnaround_m)
        covered, _ = coverage(plan, area, CALC)
        t_plan = _best_s(partial(plan_lanes, area, CALC, angle_deg=0))
        t_angle = _best_s(partial(best_angle, area, CALC, 10.0, turnaround_m=10.0))
        t_cover = _best_s(partial(coverage, plan, area, CALC))
        print(
            f"| {km2:g} | {len(plan.lanes)} | {plan.photo_count} | {t_plan:.3f} | "
            f"{t_angle:.3f} | {t_cover:.3f} | {100 * covered:.2f} | {strip:.3f} | {ratio:.3f} |"
        )

    print()
    print("| drones | split s (1 km²) | slowest / mean |")
    print("|---|---|---|")
    area = _area(1.0)
    for n in (2, 4, 8, 16):
        drones = [
            Drone(f"d{i}", (-200.0 + 30 * i, -100.0), (-200.0 + 30 * i, -100.0)) for i in range(n)
        ]
        t = time.perf_counter()
        parts = split(area, CALC, drones)
        elapsed = time.perf_counter() - t
        times = [p.total_s for p in parts]
        print(f"| {n} | {elapsed:.2f} | {max(times) / (sum(times) / n):.4f} |")


if __name__ == "__main__":
    main()
