"""Survey areas from GeoJSON and KML (a KML entity bomb refused), and a mission's path as
GeoJSON."""

from __future__ import annotations

import json

import pytest
from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from backend.survey.files.areas import (
    mission_path_geojson,
    read_geojson_polygon,
    read_kml_polygon,
)
from backend.survey.files.items import InteropError
from backend.survey.planning.schemas import SurveyRequest
from tests.support.surveys import QGC_HOME, survey_plan_items


def test_geojson_polygon_and_path() -> None:
    polygon = {"type": "Polygon", "coordinates": [[[8, 47], [8.01, 47], [8.01, 47.01], [8, 47]]]}
    feature = {"type": "FeatureCollection", "features": [{"type": "Feature", "geometry": polygon}]}
    assert read_geojson_polygon(json.dumps(feature)) == polygon
    items = survey_plan_items()
    path = mission_path_geojson(items)["geometry"]
    flown = (mavlink2.MAV_CMD_NAV_TAKEOFF, mavlink2.MAV_CMD_NAV_WAYPOINT)
    places = [i for i in items if i.command in flown]
    # the take-off is where the drone climbs (its own position), then the waypoints
    assert places[0].command == mavlink2.MAV_CMD_NAV_TAKEOFF
    assert (places[0].lat, places[0].lon) == (QGC_HOME[0], QGC_HOME[1])
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
