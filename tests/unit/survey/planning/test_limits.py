"""A survey plan's size is estimated before it is planned: never above what the planner
makes (so nothing that fits is refused), refused past the limits naming each one. (A plan's
time is bounded by killing its worker process: tests/unit/worker_pool/test_worker_pool.py.)"""

from __future__ import annotations

import math

import pytest
from shapely.geometry import box

from backend.survey.planning.camera import calculate, preset
from backend.survey.planning.limits import (
    PlanTooLarge,
    SurveyLimits,
    check_estimate,
    check_missions,
    estimate,
)
from backend.survey.planning.mission import survey_mission
from backend.survey.planning.planner import plan_lanes
from backend.survey.planning.report import best_angle
from common.geodesy import GeoPoint, LocalFrame
from tests.support.survey_shapes import SHAPES

LIMITS = SurveyLimits(survey_max_lanes=1000, survey_max_photos=20_000, survey_max_mission_items=700)


@pytest.mark.parametrize("name", sorted(SHAPES))
@pytest.mark.parametrize("altitude_m", [30.0, 80.0])
def test_the_estimate_is_never_above_the_plan(name: str, altitude_m: float) -> None:
    area = SHAPES[name]
    calc = calculate(preset("sony_a6000_16mm"), altitude_m=altitude_m)
    angle = best_angle(area, calc, 10.0, turnaround_m=10.0)
    plan = plan_lanes(area, calc, angle_deg=angle, turnaround_m=10.0)
    site = LocalFrame(47.0, 8.0, 0.0)
    takeoff = GeoPoint(47.0, 8.0, 0.0)
    items = survey_mission(plan, site, altitude_m, takeoff=takeoff, speed_ms=10.0).items
    for requested in (None, angle):  # the fewest rows over the angles, or the given one
        found = estimate(area, calc, drones=1, angle_deg=requested, per_photo=False)
        assert found.lanes <= len(plan.lanes)
        assert found.items_per_drone <= len(items)
        # Photos: within a lane's photo of the plan's (a piece's ends can round down).
        assert found.photos <= plan.photo_count + len(plan.lanes)
        assert found.photos >= 0.5 * plan.photo_count


def test_a_huge_area_is_refused_naming_every_limit_and_estimate() -> None:
    side = 4400.0
    area = box(0, 0, side, side)
    calc = calculate(preset("sony_a6000_16mm"), altitude_m=1.0)
    found = estimate(area, calc, drones=3, angle_deg=None, per_photo=False)
    assert found.lanes == math.ceil(side / calc.lane_spacing_m)
    with pytest.raises(PlanTooLarge) as refused:
        check_estimate(found, LIMITS)
    message = str(refused.value)
    assert f"about {found.photos:,} photos; the limit is 20,000 (survey_max_photos)" in message
    assert f"about {found.lanes:,} lanes; the limit is 1,000 (survey_max_lanes)" in message
    assert "(survey_max_mission_items)" in message


def test_a_mission_over_the_store_is_refused_by_drone() -> None:
    check_missions({"a": 700, "b": 12}, LIMITS)
    with pytest.raises(PlanTooLarge, match=r"b 701\); the limit is 700"):
        check_missions({"a": 700, "b": 701}, LIMITS)
