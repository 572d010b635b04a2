"""A QGroundControl Survey complex item as our survey request's fields, checked as QGC
loads it: a version QGC does not read, or a key its loaders require, is refused, named."""

from __future__ import annotations

import json
from typing import Any

from backend.survey.files.items import InteropError, json_number

# The keys QGroundControl's loaders require, with their JSON types (JsonHelper::validateKeys
# in SurveyComplexItem::_loadV4V5, TransectStyleComplexItem::_load, CameraCalc::load and
# CameraSpec::load). QGC writes a NaN double as null, and its validator lets null stand for
# a number, so this does too.
_SURVEY_KEYS = {
    "type": "string",
    "complexItemType": "string",
    "entryLocation": "number",
    "angle": "number",
    "polygon": "array",
    "TransectStyleComplexItem": "object",
}
_SURVEY_V5_KEYS = {"splitConcavePolygons": "bool"}
_TRANSECT_KEYS = {
    "version": "number",
    "TurnAroundDistance": "number",
    "CameraTriggerInTurnAround": "bool",
    "HoverAndCapture": "bool",
    "Refly90Degrees": "bool",
    "CameraCalc": "object",
    "VisualTransectPoints": "array",
    "Items": "array",
}
_TRANSECT_V2_KEYS = {"CameraShots": "number"}  # optional in version 1 (added later)
_CAMERA_CALC_KEYS = {
    "CameraName": "string",
    "AdjustedFootprintSide": "number",
    "AdjustedFootprintFrontal": "number",
    "DistanceToSurface": "number",
}
_CAMERA_CALC_V1_KEYS = {"DistanceToSurfaceRelative": "bool"}
_CAMERA_CALC_V2_KEYS = {"DistanceMode": "number"}
# A camera with figures (not the manual one): CameraCalc's second list and CameraSpec's.
_CAMERA_SPEC_KEYS = {
    "ValueSetIsDistance": "bool",
    "ImageDensity": "number",
    "FrontalOverlap": "number",
    "SideOverlap": "number",
    "SensorWidth": "number",
    "SensorHeight": "number",
    "ImageWidth": "number",
    "ImageHeight": "number",
    "FocalLength": "number",
    "Landscape": "bool",
    "FixedOrientation": "bool",
    "MinTriggerInterval": "number",
}
MANUAL_CAMERA = "Manual (no camera specs)"  # CameraCalc::canonicalManualCameraName
_RELATIVE = 1  # QGroundControlQmlGlobal::AltitudeModeRelative (DistanceMode)
_ALTITUDE_MODES = {
    0: "mixed",
    2: "absolute (AMSL)",
    3: "calculated above terrain",
    4: "terrain frame",
    5: "none",
}


def _json_type(value: Any) -> str:
    if value is None or (isinstance(value, int | float) and not isinstance(value, bool)):
        return "number"  # null is a NaN double for QGC
    for kind, python in (("bool", bool), ("string", str), ("array", list), ("object", dict)):
        if isinstance(value, python):
            return kind
    return "unknown"


def _require(raw: dict[str, Any], keys: dict[str, str], where: str) -> None:
    """InteropError naming every required key that is missing or of the wrong JSON type."""
    wrong = []
    for key, kind in keys.items():
        if key not in raw:
            wrong.append(
                f'"{key}" ({"an" if kind in ("array", "object") else "a"} {kind}) is missing'
            )
        elif _json_type(raw[key]) != kind and not (kind == "bool" and raw[key] is None):
            wrong.append(f'"{key}" must be a {kind}, not {json.dumps(raw[key])[:40]}')
    if wrong:
        raise InteropError(f"{where}: {'; '.join(wrong)}")


def _version(raw: dict[str, Any], where: str, what: str, accepted: tuple[int, ...]) -> int:
    value = raw.get("version")
    if isinstance(value, bool) or not isinstance(value, int | float) or value != int(value):
        raise InteropError(f'{where}: the {what} needs a whole "version" number')
    if int(value) not in accepted:
        known = " or ".join(str(v) for v in accepted)
        raise InteropError(
            f"{where}: {what} version {int(value)} is not one QGroundControl writes "
            f"(this hub reads version {known})"
        )
    return int(value)


def survey_fields(raw: dict[str, Any], where: str) -> dict[str, Any]:
    value = raw.get("version")
    if value in (2, 3):
        raise InteropError(
            f"{where}: survey version {value} is QGroundControl's format from before 2018 "
            "(a grid and camera object); open the plan in QGroundControl and save it again"
        )
    version = _version(raw, where, "survey", (4, 5))
    _require(raw, {**_SURVEY_KEYS, **(_SURVEY_V5_KEYS if version == 5 else {})}, where)
    if raw["type"] != "ComplexItem":
        raise InteropError(f'{where}: a survey\'s "type" is "ComplexItem", not {raw["type"]!r}')
    polygon = raw["polygon"]
    if len(polygon) < 3:
        raise InteropError(f'{where}: the survey\'s "polygon" needs at least 3 [lat, lon]')
    ring = []
    for k, point in enumerate(polygon):
        if not isinstance(point, list) or len(point) < 2:
            raise InteropError(f"{where}: polygon point {k + 1} must be [lat, lon]")
        ring.append([json_number(point[1], "longitude"), json_number(point[0], "latitude")])
    ring.append(ring[0])
    transect = raw["TransectStyleComplexItem"]
    inner = f"{where}'s TransectStyleComplexItem"
    transect_version = _version(transect, inner, "TransectStyleComplexItem", (1, 2))
    _require(
        transect, {**_TRANSECT_KEYS, **(_TRANSECT_V2_KEYS if transect_version == 2 else {})}, inner
    )
    fields: dict[str, Any] = {"area": {"type": "Polygon", "coordinates": [ring]}}
    fields.update(_camera_fields(transect["CameraCalc"], f"{inner}'s CameraCalc"))
    # QGC's grid angle is the lanes' compass heading (0 = north-south lanes); ours is
    # degrees from east (0 = east-west lanes), counter-clockwise.
    fields["angle_deg"] = (90.0 - json_number(raw["angle"], "angle")) % 180.0
    fields["turnaround_m"] = json_number(transect["TurnAroundDistance"], "TurnAroundDistance")
    fields["hover_and_capture"] = bool(transect["HoverAndCapture"])
    return fields


def _camera_fields(calc: dict[str, Any], where: str) -> dict[str, Any]:
    version = _version(calc, where, "CameraCalc", (1, 2))
    _require(
        calc,
        {**_CAMERA_CALC_KEYS, **(_CAMERA_CALC_V1_KEYS if version == 1 else _CAMERA_CALC_V2_KEYS)},
        where,
    )
    # Our surveys fly at a height above home: a plan at another altitude reference would
    # be flown at the wrong height, so it is refused rather than read as relative.
    mode = (
        (_RELATIVE if calc["DistanceToSurfaceRelative"] else 2)
        if version == 1
        else (calc["DistanceMode"])
    )
    if mode != _RELATIVE:
        named = _ALTITUDE_MODES.get(mode, f"number {mode}")
        raise InteropError(
            f"{where}: the survey's altitude mode is {named}; this hub flies surveys at a "
            "height relative to home: set the survey's altitude mode to Relative"
        )
    altitude = json_number(calc["DistanceToSurface"], "DistanceToSurface")
    if calc["CameraName"] == MANUAL_CAMERA:
        # QGC's manual camera: the spacing and trigger distance are the plan, as given.
        return {
            "camera": {
                "lane_spacing_m": json_number(
                    calc["AdjustedFootprintSide"], "AdjustedFootprintSide"
                ),
                "trigger_distance_m": json_number(
                    calc["AdjustedFootprintFrontal"], "AdjustedFootprintFrontal"
                ),
            },
            "altitude_m": altitude,
        }
    _require(calc, _CAMERA_SPEC_KEYS, where)
    fields: dict[str, Any] = {
        "camera": {
            "sensor_width_mm": json_number(calc["SensorWidth"], "SensorWidth"),
            "sensor_height_mm": json_number(calc["SensorHeight"], "SensorHeight"),
            "image_width_px": int(json_number(calc["ImageWidth"], "ImageWidth")),
            "image_height_px": int(json_number(calc["ImageHeight"], "ImageHeight")),
            "focal_length_mm": json_number(calc["FocalLength"], "FocalLength"),
            "landscape": bool(calc["Landscape"]),
        },
        "side_overlap_pct": json_number(calc["SideOverlap"], "SideOverlap"),
        "front_overlap_pct": json_number(calc["FrontalOverlap"], "FrontalOverlap"),
    }
    if calc["ValueSetIsDistance"]:
        fields["altitude_m"] = altitude
    else:
        fields["gsd_cm"] = json_number(calc["ImageDensity"], "ImageDensity")
    return fields
