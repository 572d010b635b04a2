"""A plan with a QGC Survey complex item imports as a survey request with QGC's numbers;
a survey QGC would not load is refused naming what is wrong; a manual camera keeps its
spacing."""

from __future__ import annotations

import json
import math
from collections.abc import Callable
from typing import Any

import pytest
from pydantic import ValidationError
from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from backend.survey.files.items import InteropError
from backend.survey.files.qgc_plan import read_qgc_plan_items, read_qgc_survey
from backend.survey.planning.camera import calculate
from backend.survey.planning.schemas import SurveyRequest
from backend.survey.planning.survey import Fleet, _camera, plan_survey
from common.geodesy import GeoPoint
from tests.support.surveys import QGC_DATA, QGC_HOME


def test_a_qgc_survey_imports_with_its_polygon_and_camera_giving_qgcs_numbers() -> None:
    text = (QGC_DATA / "survey.plan").read_text()
    fields = read_qgc_survey(text)
    request = SurveyRequest.model_validate({**fields, "vehicle_ids": ["d1"]})
    assert request.altitude_m == 80
    assert request.turnaround_m == 10
    # QGC's angle 0 runs the lanes north-south; ours, 90.
    assert request.angle_deg == 90
    ring = request.area.coordinates[0]
    assert ring[0] == [8.5450, 47.3980]
    assert ring[-1] == ring[0]
    calc = calculate(
        _camera(request),
        altitude_m=request.altitude_m,
        side_overlap_pct=request.side_overlap_pct,
        front_overlap_pct=request.front_overlap_pct,
    )
    saved = json.loads(text)["mission"]["items"][1]["TransectStyleComplexItem"]["CameraCalc"]
    assert calc.lane_spacing_m == pytest.approx(saved["AdjustedFootprintSide"])
    assert calc.trigger_distance_m == pytest.approx(saved["AdjustedFootprintFrontal"])
    assert calc.gsd_cm == pytest.approx(saved["ImageDensity"])
    # ...but its items are not flown as simple items: that would drop the survey
    with pytest.raises(InteropError, match="mission item 2 is a survey complex item"):
        read_qgc_plan_items(text)


def _survey_plan(change: Callable[[dict[str, Any]], None]) -> str:
    """survey.plan with its Survey item changed by `change`."""
    document = json.loads((QGC_DATA / "survey.plan").read_text())
    change(document["mission"]["items"][1])
    return json.dumps(document)


def _manual(survey: dict[str, Any]) -> None:
    # What QGC saves for its manual camera (CameraCalc::save): no camera figures, no
    # overlaps, the spacing and trigger distance as the plan.
    survey["TransectStyleComplexItem"]["CameraCalc"] = {
        "AdjustedFootprintFrontal": 25,
        "AdjustedFootprintSide": 25,
        "CameraName": "Manual (no camera specs)",
        "DistanceMode": 1,
        "DistanceToSurface": 50,
        "version": 2,
    }


BROKEN_SURVEYS: dict[str, tuple[Callable[[dict[str, Any]], None], str]] = {
    "no Items": (
        lambda s: s["TransectStyleComplexItem"].pop("Items"),
        r'mission item 2\'s TransectStyleComplexItem: "Items" \(an array\) is missing',
    ),
    "survey version 9": (
        lambda s: s.update(version=9),
        r"mission item 2: survey version 9 is not one QGroundControl writes \(this hub reads "
        r"version 4 or 5\)",
    ),
    "survey version 3": (lambda s: s.update(version=3), "survey version 3 is QGroundControl's"),
    "no version": (lambda s: s.pop("version"), 'the survey needs a whole "version" number'),
    "no TransectStyleComplexItem": (
        lambda s: s.pop("TransectStyleComplexItem"),
        '"TransectStyleComplexItem" \\(an object\\) is missing',
    ),
    "transect version 3": (
        lambda s: s["TransectStyleComplexItem"].update(version=3),
        "TransectStyleComplexItem version 3 is not one",
    ),
    "no CameraCalc": (
        lambda s: s["TransectStyleComplexItem"].pop("CameraCalc"),
        '"CameraCalc" \\(an object\\) is missing',
    ),
    "camera figures missing": (
        lambda s: [s["TransectStyleComplexItem"]["CameraCalc"].pop(k) for k in ("FocalLength",)],
        '\'s CameraCalc: "FocalLength" \\(a number\\) is missing',
    ),
    "camera calc version 7": (
        lambda s: s["TransectStyleComplexItem"]["CameraCalc"].update(version=7),
        "CameraCalc version 7 is not one",
    ),
    "angle a string": (lambda s: s.update(angle="north"), '"angle" must be a number, not "north"'),
    "no splitConcavePolygons in version 5": (
        lambda s: s.pop("splitConcavePolygons"),
        '"splitConcavePolygons" \\(a bool\\) is missing',
    ),
    "terrain following": (
        lambda s: s["TransectStyleComplexItem"]["CameraCalc"].update(DistanceMode=3),
        "altitude mode is calculated above terrain; this hub flies surveys at a height "
        "relative to home",
    ),
}


@pytest.mark.parametrize("case", BROKEN_SURVEYS.values(), ids=BROKEN_SURVEYS.keys())
def test_a_survey_qgc_would_not_load_is_refused_naming_what_is_wrong(
    case: tuple[Callable[[dict[str, Any]], None], str],
) -> None:
    change, refusal = case
    with pytest.raises(InteropError, match=refusal):
        read_qgc_survey(_survey_plan(change))


def test_a_version_4_survey_needs_no_split_concave_polygons() -> None:
    def version_4(survey: dict[str, Any]) -> None:
        survey.update(version=4)
        survey.pop("splitConcavePolygons")

    assert read_qgc_survey(_survey_plan(version_4))["altitude_m"] == 80


def test_a_manual_camera_keeps_the_plans_spacing_and_trigger_distance() -> None:
    fields = read_qgc_survey(_survey_plan(_manual))
    assert fields["camera"] == {"lane_spacing_m": 25, "trigger_distance_m": 25}
    assert fields["altitude_m"] == 50
    request = SurveyRequest.model_validate({**fields, "vehicle_ids": ["d1"]})
    home = GeoPoint(QGC_HOME[0], QGC_HOME[1], QGC_HOME[2])
    survey = plan_survey(request, [Fleet("d1", home, home)])
    assert survey.calc.lane_spacing_m == 25
    assert survey.calc.trigger_distance_m == 25
    assert survey.calc.gsd_cm is None
    items = survey.parts[0].items
    triggers = [i for i in items if i.command == mavlink2.MAV_CMD_DO_SET_CAM_TRIGG_DIST]
    assert {i.param1 for i in triggers} == {25, 0}  # on at 25 m, then off
    waypoints = [i for i in items if i.command == mavlink2.MAV_CMD_NAV_WAYPOINT]
    assert {i.alt for i in waypoints} == {50}
    # The lanes run north-south (QGC's angle 0): neighbours are 25 m apart in longitude.
    assert request.angle_deg == 90
    lanes = survey.parts[0].lane_paths
    (a_lat, a_lon), (_, b_lon) = lanes[0][0], lanes[1][0]
    across = abs(b_lon - a_lon) * 111_320 * math.cos(math.radians(a_lat))
    assert across == pytest.approx(25, abs=0.2)


def test_a_manual_camera_needs_an_altitude_not_a_gsd() -> None:
    fields = read_qgc_survey(_survey_plan(_manual))
    fields.pop("altitude_m")
    with pytest.raises(ValidationError, match="a manual camera has no sensor"):
        SurveyRequest.model_validate({**fields, "gsd_cm": 2, "vehicle_ids": ["d1"]})
