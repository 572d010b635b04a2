"""Other tools' files: our `.plan` export parses back to the same items and has the fields
QGC requires; QGC's own plan and a plan with a Survey complex item import; WPL, GeoJSON and
KML likewise."""

from __future__ import annotations

import json
from pathlib import Path

import jsonschema_rs
import pytest
from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from backend.missions.survey.camera import calculate
from backend.missions.survey.interop import (
    InteropError,
    mission_path_geojson,
    read_geojson_polygon,
    read_kml_polygon,
    read_qgc_plan_items,
    read_qgc_survey,
    read_wpl,
    to_qgc_plan,
    to_wpl,
)
from backend.missions.survey.schemas import SurveyRequest
from backend.missions.survey.service import Fleet, _camera, plan_survey
from common.geodesy import GeoPoint
from protocol.messages import MissionItem

DATA = Path(__file__).resolve().parents[2] / "data" / "qgc"
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
