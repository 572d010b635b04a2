"""Other tools' files: our `.plan` export parses back to the same items and has the fields
QGC requires; QGC's own plan and a plan with a Survey complex item import; WPL, GeoJSON and
KML likewise."""

from __future__ import annotations

import json
import math
from collections.abc import Callable
from pathlib import Path
from typing import Any

import jsonschema_rs
import pytest
from pydantic import ValidationError
from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from backend.survey.files.areas import (
    mission_path_geojson,
    read_geojson_polygon,
    read_kml_polygon,
)
from backend.survey.files.items import InteropError
from backend.survey.files.qgc_plan import read_qgc_plan_items, read_qgc_survey, to_qgc_plan
from backend.survey.files.wpl import to_wpl
from backend.survey.planning.camera import calculate
from backend.survey.planning.schemas import SurveyRequest
from backend.survey.planning.survey import Fleet, _camera, plan_survey
from common.geodesy import GeoPoint
from protocol.messages import MissionItem
from tests.support.surveys import read_wpl

DATA = Path(__file__).resolve().parents[3] / "data" / "qgc"
HOME = (47.3977, 8.5456, 488.0)


def _survey_items() -> list[MissionItem]:
    fields = read_qgc_survey((DATA / "survey.plan").read_text())
    request = SurveyRequest.model_validate({**fields, "vehicle_ids": ["d1"]})
    home = GeoPoint(HOME[0], HOME[1], HOME[2])
    survey = plan_survey(request, [Fleet("d1", home, home)])
    return survey.parts[0].items


def _same(a: list[MissionItem], b: list[MissionItem]) -> None:
    assert len(a) == len(b)
    for x, y in zip(a, b, strict=True):
        assert (x.command, x.frame, x.autocontinue) == (y.command, y.frame, y.autocontinue)
        for field in ("param1", "param2", "param3", "param4", "lat", "lon", "alt"):
            assert getattr(x, field) == pytest.approx(getattr(y, field), abs=1e-7), field


def test_our_plan_export_has_qgcs_fields_and_parses_back_to_the_same_items() -> None:
    items = _survey_items()
    document = to_qgc_plan(items, HOME)
    schema = json.loads((DATA / "plan.schema.json").read_text())
    jsonschema_rs.validate(schema, document)
    commands = {item.command for item in items}
    assert mavlink2.MAV_CMD_DO_SET_CAM_TRIGG_DIST in commands
    _same(read_qgc_plan_items(json.dumps(document)), items)


def test_qgcs_own_plan_imports() -> None:
    items = read_qgc_plan_items((DATA / "simple_square.plan").read_text())
    assert items[0].command == mavlink2.MAV_CMD_NAV_TAKEOFF
    assert items[1].lat == pytest.approx(47.398742)
    assert items[1].frame == mavlink2.MAV_FRAME_GLOBAL_RELATIVE_ALT
    # QGC's null yaw is MAVLink's NaN, "keep the heading": unset, not 0 (north on PX4).
    assert [item.param4 for item in items] == [None] * len(items)


def test_a_qgc_null_altitude_is_refused_naming_the_item_not_read_as_0() -> None:
    refusal = r"mission item 3 .*param 7 \(altitude\) is empty \(null\)"
    with pytest.raises(InteropError, match=refusal):
        read_qgc_plan_items((DATA / "null_altitude.plan").read_text())


def test_a_qgc_survey_imports_with_its_polygon_and_camera_giving_qgcs_numbers() -> None:
    text = (DATA / "survey.plan").read_text()
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


def test_wpl_round_trip() -> None:
    items = _survey_items()
    text = to_wpl(items, HOME)
    assert text.startswith("QGC WPL 110\n0\t1\t0\t16\t")
    home, back = read_wpl(text)
    assert home == pytest.approx(HOME)
    _same(back, items)


def test_geojson_polygon_and_path() -> None:
    polygon = {"type": "Polygon", "coordinates": [[[8, 47], [8.01, 47], [8.01, 47.01], [8, 47]]]}
    feature = {"type": "FeatureCollection", "features": [{"type": "Feature", "geometry": polygon}]}
    assert read_geojson_polygon(json.dumps(feature)) == polygon
    items = _survey_items()
    path = mission_path_geojson(items)["geometry"]
    flown = (mavlink2.MAV_CMD_NAV_TAKEOFF, mavlink2.MAV_CMD_NAV_WAYPOINT)
    places = [i for i in items if i.command in flown]
    # the take-off is where the drone climbs (its own position), then the waypoints
    assert places[0].command == mavlink2.MAV_CMD_NAV_TAKEOFF
    assert (places[0].lat, places[0].lon) == (HOME[0], HOME[1])
    assert path["coordinates"] == [[w.lon, w.lat, w.alt] for w in places]
    with pytest.raises(InteropError, match="no Polygon"):
        read_geojson_polygon('{"type": "Point", "coordinates": [0, 0]}')


KML = """<?xml version="1.0" encoding="UTF-8"?>
<kml xmlns="http://www.opengis.net/kml/2.2"><Document><Placemark><name>field</name>
<Polygon><outerBoundaryIs><LinearRing><coordinates>
8.545,47.398,0 8.55,47.398,0 8.55,47.401,0 8.545,47.401,0 8.545,47.398,0
</coordinates></LinearRing></outerBoundaryIs>
<innerBoundaryIs><LinearRing><coordinates>
8.547,47.399 8.548,47.399 8.548,47.400 8.547,47.399
</coordinates></LinearRing></innerBoundaryIs></Polygon></Placemark></Document></kml>"""


def test_a_kml_polygon_from_google_earth_imports_with_its_hole() -> None:
    polygon = read_kml_polygon(KML)
    outline, hole = polygon["coordinates"]
    assert outline[0] == [8.545, 47.398]
    assert len(outline) == 5
    assert hole[0] == hole[-1] == [8.547, 47.399]
    request = SurveyRequest.model_validate(
        {"area": polygon, "camera": "sony_a6000_16mm", "altitude_m": 60, "vehicle_ids": ["d"]}
    )
    assert len(request.area.coordinates) == 2


def test_a_kml_file_with_an_entity_bomb_is_refused() -> None:
    entities = "".join(
        f'<!ENTITY {c} "&{p};&{p};&{p};&{p};&{p};&{p};&{p};&{p};">'
        for p, c in zip("abcdefg", "bcdefgh", strict=True)
    )
    bomb = (
        f'<?xml version="1.0"?><!DOCTYPE kml [<!ENTITY a "aaaaaaaaaa">{entities}]>'
        "<kml><Polygon><outerBoundaryIs><coordinates>&h;</coordinates>"
        "</outerBoundaryIs></Polygon></kml>"
    )
    with pytest.raises(InteropError):
        read_kml_polygon(bomb)


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("{", "invalid JSON"),
        ('{"fileType": "Fence"}', '"fileType" must be "Plan"'),
        ('{"fileType": "Plan", "mission": {"items": [{"type": "SimpleItem"}]}}', "7 params"),
    ],
)
def test_bad_plan_files_are_refused_saying_why(text: str, message: str) -> None:
    with pytest.raises(InteropError, match=message):
        read_qgc_plan_items(text)


def _survey_plan(change: Callable[[dict[str, Any]], None]) -> str:
    """survey.plan with its Survey item changed by `change`."""
    document = json.loads((DATA / "survey.plan").read_text())
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
    home = GeoPoint(HOME[0], HOME[1], HOME[2])
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
