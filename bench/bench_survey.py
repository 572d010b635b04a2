"""Survey planning benchmark: planning time for square-ish areas of 0.1, 1 and 10 km²
(the bar is 1 km² in at most 1 s), the path length against its lower bound on the test
shapes, and the fleet split's time for 2 to 16 drones over 1 km² with the slowest drone's
time / mean.

    .venv/bin/python bench/bench_survey.py

"plan" is one lane plan at a given angle; "auto angle" is report.best_angle (every 5°,
branch and bound); "coverage" is the footprint coverage check (both figures);
"all" is the three in a row, as a survey preview runs them. "path / bound" is the path
length over bound.lower_bound_m (what any lane plan on those rows must fly; the bar is
1.05): at 0° for the quadrilaterals, and the worst over every 15° for the test shapes.
Each time is the median of 5 runs. Prints Markdown tables; asserts nothing.
"""

from __future__ import annotations

import math
import statistics
import sys
import time
from collections.abc import Callable
from functools import partial
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from shapely.geometry import Polygon

from backend.survey.planning.bound import lower_bound_m
from backend.survey.planning.camera import calculate, preset
from backend.survey.planning.coverage import coverage
from backend.survey.planning.planner import plan_lanes
from backend.survey.planning.report import best_angle
from backend.survey.planning.split import Drone, split
from tests.support.survey_shapes import SHAPES, shape

CALC = calculate(preset("sony_a6000_16mm"), gsd_cm=2.0, side_overlap_pct=70, front_overlap_pct=80)


def _median_s(call: Callable[[], object]) -> float:
    runs = []
    for _ in range(5):
        t = time.perf_counter()
        call()
        runs.append(time.perf_counter() - t)
    return statistics.median(runs)


def _area(km2: float) -> Polygon:
    # A slanted quadrilateral, so lanes meet its edges at an angle.
    s = math.sqrt(km2) * 1000
    return Polygon([(0, 0), (s, 0.1 * s), (1.05 * s, s), (-0.05 * s, 0.95 * s)])


# The unit tests' shapes (tests/support/survey_shapes.py), at 100 m.
SHAPE_CALC = calculate(
    preset("sony_a6000_16mm"), altitude_m=100, side_overlap_pct=70, front_overlap_pct=80
)


def _all(area: Polygon) -> None:
    angle = best_angle(area, CALC, 10.0, turnaround_m=10.0)
    coverage(plan_lanes(area, CALC, angle_deg=angle), area, CALC)


def main() -> None:
    print(f"camera {CALC.camera.name}, GSD {CALC.gsd_cm} cm, spacing {CALC.lane_spacing_m:.1f} m")
    print(
        "| area km² | lanes | photos | plan s | auto angle s | coverage s | all s | covered % "
        "| path / bound |"
    )
    print("|---|---|---|---|---|---|---|---|---|")
    for km2 in (0.1, 1.0, 10.0):
        area = _area(km2)
        plan = plan_lanes(area, CALC, angle_deg=0)
        ratio = plan.path_length_m / lower_bound_m(area, CALC, 0.0, plan.turnaround_m)
        covered, _ = coverage(plan, area, CALC)
        t_plan = _median_s(partial(plan_lanes, area, CALC, angle_deg=0))
        t_angle = _median_s(partial(best_angle, area, CALC, 10.0, turnaround_m=10.0))
        t_cover = _median_s(partial(coverage, plan, area, CALC))
        t_all = _median_s(partial(_all, area))
        print(
            f"| {km2:g} | {len(plan.lanes)} | {plan.photo_count} | {t_plan:.3f} | "
            f"{t_angle:.3f} | {t_cover:.3f} | {t_all:.3f} | {100 * covered:.2f} | {ratio:.3f} |"
        )

    print()
    print("| shape | path / bound, worst of 0-165° | at angle |")
    print("|---|---|---|")
    for name in [*SHAPES, "zone-straddling"]:
        area = shape(name)
        worst = max(
            (
                plan_lanes(area, SHAPE_CALC, angle_deg=angle).path_length_m
                / lower_bound_m(area, SHAPE_CALC, angle, 10.0),
                angle,
            )
            for angle in range(0, 180, 15)
        )
        print(f"| {name} | {worst[0]:.3f} | {worst[1]}° |")

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
