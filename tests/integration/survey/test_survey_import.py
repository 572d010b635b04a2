"""A QGroundControl survey through the hub's REST API: a plan QGC would not load is a 422
naming what is wrong, a manual camera's spacing and trigger distance survive the import, and
a camera outside a limit is refused with that limit first (issue #35)."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import httpx

PLAN = Path(__file__).resolve().parents[2] / "data" / "qgc" / "survey.plan"
AREA = {
    "type": "Polygon",
    "coordinates": [[[8.545, 47.398], [8.55, 47.398], [8.55, 47.401], [8.545, 47.398]]],
}


def _import(api: httpx.Client, survey: dict[str, Any]) -> httpx.Response:
    document = json.loads(PLAN.read_text())
    document["mission"]["items"][1] = survey
    return api.post(
        "/api/v1/surveys/import", json={"format": "plan", "content": json.dumps(document)}
    )


def _survey() -> dict[str, Any]:
    survey: dict[str, Any] = json.loads(PLAN.read_text())["mission"]["items"][1]
    return survey


def test_a_malformed_or_unknown_version_survey_is_a_422_naming_what_is_wrong(
    admin_api: httpx.Client,
) -> None:
    no_items = _survey()
    del no_items["TransectStyleComplexItem"]["Items"]
    response = _import(admin_api, no_items)
    assert response.status_code == 422, response.text
    assert '"Items" (an array) is missing' in str(response.json())

    version_9 = {**_survey(), "version": 9}
    response = _import(admin_api, version_9)
    assert response.status_code == 422, response.text
    assert "survey version 9 is not one QGroundControl writes" in response.text

    assert _import(admin_api, _survey()).status_code == 200


def test_a_manual_camera_imports_with_its_spacing_and_trigger_distance(
    admin_api: httpx.Client,
) -> None:
    manual = _survey()
    manual["TransectStyleComplexItem"]["CameraCalc"] = {
        "AdjustedFootprintFrontal": 25,
        "AdjustedFootprintSide": 25,
        "CameraName": "Manual (no camera specs)",
        "DistanceMode": 1,
        "DistanceToSurface": 50,
        "version": 2,
    }
    response = _import(admin_api, manual)
    assert response.status_code == 200, response.text
    fields = response.json()
    assert fields["camera"] == {"lane_spacing_m": 25, "trigger_distance_m": 25}
    assert fields["altitude_m"] == 50


# QGroundControl's Flir Duo R preset (src/Camera/CameraMetaData.cc): a 160 x 120 mm
# "sensor" (its figures are for the thermal core's field of view), past our 100 mm limit.
FLIR_DUO_R = {
    "sensor_width_mm": 160,
    "sensor_height_mm": 120,
    "image_width_px": 1920,
    "image_height_px": 1080,
    "focal_length_mm": 1.9,
}


def test_a_camera_outside_a_limit_is_refused_with_that_limit_first(
    admin_api: httpx.Client,
) -> None:
    body = {"area": AREA, "camera": FLIR_DUO_R, "altitude_m": 50, "vehicle_ids": ["v1"]}
    response = admin_api.post("/api/v1/surveys/preview", json=body)
    assert response.status_code == 422, response.text
    first = response.json()["detail"][0]
    assert first["loc"] == ["body", "camera", "model", "sensor_width_mm"]
    assert first["msg"] == "Input should be less than or equal to 100"
    assert all(error["type"] != "string_type" for error in response.json()["detail"])
    # a manual camera's figures are checked as a manual camera's
    body["camera"] = {"lane_spacing_m": -1, "trigger_distance_m": 10}
    first = admin_api.post("/api/v1/surveys/preview", json=body).json()["detail"][0]
    assert first["loc"] == ["body", "camera", "manual", "lane_spacing_m"]
