"""The survey service end to end without the hub: a request and where the drones are in,
one checked-ready mission per drone and the coverage out; a drone far from the area is
refused by name."""

from __future__ import annotations

import pytest
from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from backend.survey.planning.planner import PlanError
from backend.survey.planning.schemas import SurveyRequest
from backend.survey.planning.survey import Fleet, plan_survey
from common.geodesy import GeoPoint

RING = [[8.0, 47.0], [8.004, 47.0], [8.004, 47.003], [8.0, 47.003], [8.0, 47.0]]


def _request(**changes: object) -> SurveyRequest:
    body: dict[str, object] = {
        "area": {"type": "Polygon", "coordinates": [RING]},
        "camera": "dji_phantom4_pro",
        "gsd_cm": 2.0,
        "vehicle_ids": ["a", "b"],
    }
    body.update(changes)
    return SurveyRequest.model_validate(body)


def _fleet(lat: float = 46.999) -> list[Fleet]:
    return [
        Fleet("a", GeoPoint(lat, 8.0), GeoPoint(lat, 8.0)),
        Fleet("b", GeoPoint(lat, 8.001), GeoPoint(lat, 8.001)),
    ]


def test_each_drone_gets_a_mission_and_the_photos_cover_the_area() -> None:
    survey = plan_survey(_request(), _fleet())
    assert survey.coverage == pytest.approx(1.0)
    assert survey.coverage_at_overlaps == pytest.approx(1.0)
    assert survey.calc.altitude_m == pytest.approx(72.96)
    assert 0 <= survey.angle_deg < 180
    assert [p.part.drone.name for p in survey.parts] == ["a", "b"]
    for planned in survey.parts:
        assert planned.items[0].command == mavlink2.MAV_CMD_NAV_TAKEOFF
        assert planned.items[-1].command == mavlink2.MAV_CMD_NAV_RETURN_TO_LAUNCH


def test_a_per_photo_camera_gets_one_capture_per_photo() -> None:
    survey = plan_survey(_request(camera="micasense_rededge_mx", gsd_cm=5.0), _fleet())
    for planned in survey.parts:
        captures = [i for i in planned.items if i.command == mavlink2.MAV_CMD_DO_DIGICAM_CONTROL]
        assert len(captures) == planned.part.plan.photo_count


def test_a_drone_far_from_the_area_is_refused_by_name() -> None:
    with pytest.raises(PlanError, match=r"vehicle a is .* km from the area"):
        plan_survey(_request(), _fleet(lat=46.5))
