"""Other tools' files: QGroundControl `.plan` (simple items, and the polygon and camera of a
Survey complex item), `QGC WPL 110` waypoint files, GeoJSON polygons and paths, and KML
polygons (areas drawn in Google Earth).

Pure: text or parsed JSON in, our types out, and back. Every reader raises InteropError with
a message saying what is wrong and where.
"""

from __future__ import annotations

import json
import math
import xml.etree.ElementTree as ElementTree
from collections.abc import Sequence
from typing import Any
from xml.parsers import expat

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from protocol.messages import MissionItem

MAX_FILE_BYTES = 5_000_000
# Commands whose params 5-7 are a position; for the others they are plain numbers, which
# MISSION_ITEM_INT carries unscaled in x and y (our MissionItem holds x as lat * 1e7).
_POSITIONLESS_FRAME = mavlink2.MAV_FRAME_MISSION
_KML = "{http://www.opengis.net/kml/2.2}"


class InteropError(ValueError):
    """A file that cannot be read; the message says what to change."""


class TooManyVertices(InteropError):
    """An area file whose polygon has more vertices than the caller takes: counted
    before the coordinates are parsed."""

    def __init__(self, count: int, limit: int) -> None:
        super().__init__(f"the area has {count} vertices; at most {limit} are allowed")
        self.count = count
        self.limit = limit

    def __reduce__(self) -> tuple[type[TooManyVertices], tuple[int, int]]:
        # Raised in a worker process and again in the hub's: rebuilt from both numbers.
        return TooManyVertices, (self.count, self.limit)


def _check_vertices(count: int, limit: int | None) -> None:
    if limit is not None and count > limit:
        raise TooManyVertices(count, limit)


def read_area_file(kind: str, text: str, max_vertices: int | None = None) -> dict[str, Any]:
    """A survey request's fields from an area file: "plan" (a QGC Survey: its area,
    camera and settings), "kml" or "geojson" (the area)."""
    if kind == "plan":
        return read_qgc_survey(text, max_vertices)
    if kind == "kml":
        return {"area": read_kml_polygon(text, max_vertices)}
    if kind == "geojson":
        return {"area": read_geojson_polygon(text, max_vertices)}
    raise InteropError(f"unknown area file format {kind!r}; plan, kml or geojson")


def _number(value: Any, where: str) -> float:
    if value is None:
        return math.nan  # QGC writes NaN as null
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise InteropError(f"{where} must be a number, not {value!r}")
    return float(value)


def _params_to_item(
    command: int, frame: int, params: Sequence[float], autocontinue: bool
) -> MissionItem:
    # QGC's null (NaN) is "unset": kept as null for params 1-4 (the mission rules say where
    # a command allows it), refused for a position, never read as 0 (a yaw north, 0 m AMSL).
    for index, name in ((4, "latitude"), (5, "longitude"), (6, "altitude")):
        if math.isnan(params[index]):
            raise ValueError(f"param {index + 1} ({name}) is empty (null)")
    p = list(params)
    if frame == _POSITIONLESS_FRAME:
        lat, lon = p[4] / 1e7, p[5] / 1e7  # unscaled param5/param6 as MISSION_ITEM_INT x/y
    else:
        lat, lon = p[4], p[5]
    return MissionItem(
        command=command,
        frame=frame,
        param1=_unset(p[0]),
        param2=_unset(p[1]),
        param3=_unset(p[2]),
        param4=_unset(p[3]),
        lat=lat,
        lon=lon,
        alt=p[6],
        autocontinue=autocontinue,
    )


def _unset(value: float) -> float | None:
    return None if math.isnan(value) else value


def _item_params(item: MissionItem) -> list[float | None]:
    if item.frame == _POSITIONLESS_FRAME:
        five, six = float(round(item.lat * 1e7)), float(round(item.lon * 1e7))
    else:
        five, six = item.lat, item.lon
    return [item.param1, item.param2, item.param3, item.param4, five, six, item.alt]


# -- QGroundControl .plan ------------------------------------------------------------------


def to_qgc_plan(
    items: Sequence[MissionItem],
    home: tuple[float, float, float],
    *,
    cruise_speed_ms: float = 15.0,
    hover_speed_ms: float = 5.0,
) -> dict[str, Any]:
    """A plan file QGC opens: `fileType` Plan, version 1, mission version 2 with
    ArduPilot (firmwareType 3) multirotor (vehicleType 2) and simple items."""
    simple = []
    for number, item in enumerate(items, start=1):
        entry: dict[str, Any] = {
            "type": "SimpleItem",
            "autoContinue": item.autocontinue,
            "command": item.command,
            "doJumpId": number,
            "frame": item.frame,
            "params": _item_params(item),
        }
        if item.frame != _POSITIONLESS_FRAME:
            entry["Altitude"] = item.alt
            entry["AltitudeMode"] = 1 if item.frame == mavlink2.MAV_FRAME_GLOBAL_RELATIVE_ALT else 2
            entry["AMSLAltAboveTerrain"] = None
        simple.append(entry)
    return {
        "fileType": "Plan",
        "version": 1,
        "groundStation": "fleet-gcs",
        "mission": {
            "version": 2,
            "firmwareType": mavlink2.MAV_AUTOPILOT_ARDUPILOTMEGA,
            "vehicleType": mavlink2.MAV_TYPE_QUADROTOR,
            "cruiseSpeed": cruise_speed_ms,
            "hoverSpeed": hover_speed_ms,
            "globalPlanAltitudeMode": 1,
            "plannedHomePosition": list(home),
            "items": simple,
        },
        "geoFence": {"circles": [], "polygons": [], "version": 2},
        "rallyPoints": {"points": [], "version": 2},
    }


def _plan_document(text: str | bytes) -> dict[str, Any]:
    if len(text) > MAX_FILE_BYTES:
        raise InteropError(f"the file is larger than {MAX_FILE_BYTES // 1_000_000} MB")
    try:
        document = json.loads(text)
    except (ValueError, RecursionError) as error:  # nesting past the parser's depth too
        raise InteropError(f"not a .plan file: invalid JSON ({error})") from None
    if not isinstance(document, dict) or document.get("fileType") != "Plan":
        raise InteropError('not a .plan file: its "fileType" must be "Plan"')
    mission = document.get("mission")
    if not isinstance(mission, dict) or not isinstance(mission.get("items"), list):
        raise InteropError('the plan has no "mission" with "items"')
    return document


def read_qgc_plan_items(text: str | bytes) -> list[MissionItem]:
    """A plan's simple items (a complex item is refused, named: flying part of a survey
    would be worse than none; import its polygon with read_qgc_survey instead)."""
    document = _plan_document(text)
    items = []
    for i, raw in enumerate(document["mission"]["items"]):
        where = f"mission item {i + 1}"
        if not isinstance(raw, dict):
            raise InteropError(f"{where} must be an object")
        if raw.get("type") != "SimpleItem":
            kind = raw.get("complexItemType", raw.get("type"))
            raise InteropError(f"{where} is a {kind} complex item; open it as a survey area")
        params = raw.get("params")
        if not isinstance(params, list) or len(params) != 7:
            raise InteropError(f"{where} needs 7 params")
        numbers = [_number(p, f"{where} param {k + 1}") for k, p in enumerate(params)]
        try:
            items.append(
                _params_to_item(
                    int(raw["command"]),
                    int(raw["frame"]),
                    numbers,
                    bool(raw.get("autoContinue", True)),
                )
            )
        except (KeyError, TypeError, ValueError) as error:
            raise InteropError(f"{where} is not a mission item: {error}") from None
    return items


def read_qgc_survey(text: str | bytes, max_vertices: int | None = None) -> dict[str, Any]:
    """The first Survey complex item of a plan as our survey request's fields: the area
    (GeoJSON), the camera's figures (or a manual camera's spacing and trigger distance),
    altitude or GSD, overlaps, angle, turnaround and hover-and-capture (QGC's CameraCalc and
    TransectStyleComplexItem keys). The item is checked as QGC loads it: a version QGC
    does not read, or a key its loaders require, is refused, named."""
    document = _plan_document(text)
    for i, raw in enumerate(document["mission"]["items"]):
        if isinstance(raw, dict) and raw.get("complexItemType") == "survey":
            polygon = raw.get("polygon")
            _check_vertices(len(polygon) if isinstance(polygon, list) else 0, max_vertices)
            return _survey_fields(raw, f"mission item {i + 1}")
    raise InteropError("the plan has no Survey complex item")


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


def _survey_fields(raw: dict[str, Any], where: str) -> dict[str, Any]:
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
        ring.append([_number(point[1], "longitude"), _number(point[0], "latitude")])
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
    fields["angle_deg"] = (90.0 - _number(raw["angle"], "angle")) % 180.0
    fields["turnaround_m"] = _number(transect["TurnAroundDistance"], "TurnAroundDistance")
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
    altitude = _number(calc["DistanceToSurface"], "DistanceToSurface")
    if calc["CameraName"] == MANUAL_CAMERA:
        # QGC's manual camera: the spacing and trigger distance are the plan, as given.
        return {
            "camera": {
                "lane_spacing_m": _number(calc["AdjustedFootprintSide"], "AdjustedFootprintSide"),
                "trigger_distance_m": _number(
                    calc["AdjustedFootprintFrontal"], "AdjustedFootprintFrontal"
                ),
            },
            "altitude_m": altitude,
        }
    _require(calc, _CAMERA_SPEC_KEYS, where)
    fields: dict[str, Any] = {
        "camera": {
            "sensor_width_mm": _number(calc["SensorWidth"], "SensorWidth"),
            "sensor_height_mm": _number(calc["SensorHeight"], "SensorHeight"),
            "image_width_px": int(_number(calc["ImageWidth"], "ImageWidth")),
            "image_height_px": int(_number(calc["ImageHeight"], "ImageHeight")),
            "focal_length_mm": _number(calc["FocalLength"], "FocalLength"),
            "landscape": bool(calc["Landscape"]),
        },
        "side_overlap_pct": _number(calc["SideOverlap"], "SideOverlap"),
        "front_overlap_pct": _number(calc["FrontalOverlap"], "FrontalOverlap"),
    }
    if calc["ValueSetIsDistance"]:
        fields["altitude_m"] = altitude
    else:
        fields["gsd_cm"] = _number(calc["ImageDensity"], "ImageDensity")
    return fields


# -- QGC WPL 110 ---------------------------------------------------------------------------

WPL_HEADER = "QGC WPL 110"


def to_wpl(items: Sequence[MissionItem], home: tuple[float, float, float]) -> str:
    """Line 0 is home (absolute altitude), then one line per item, tab-separated: index,
    current, frame, command, param1-4, x/lat, y/lon, z/alt, autocontinue."""
    lines = [WPL_HEADER]
    lat, lon, alt = home
    lines.append(f"0\t1\t0\t16\t0\t0\t0\t0\t{lat:.8f}\t{lon:.8f}\t{alt:.6f}\t1")
    for number, item in enumerate(items, start=1):
        p = _item_params(item)
        fields = [number, 0, item.frame, item.command, *p, int(item.autocontinue)]
        lines.append("\t".join(_wpl_number(v) for v in fields))
    return "\n".join(lines) + "\n"


def _wpl_number(value: float | int | None) -> str:
    if value is None:
        return "nan"  # unset, as QGC and MAVProxy write NaN
    if isinstance(value, int):
        return str(value)
    return f"{value:.8f}".rstrip("0").rstrip(".") or "0"


def read_wpl(text: str) -> tuple[tuple[float, float, float] | None, list[MissionItem]]:
    """(home, items after home) from a `QGC WPL 110` file."""
    if len(text) > MAX_FILE_BYTES:
        raise InteropError(f"the file is larger than {MAX_FILE_BYTES // 1_000_000} MB")
    lines = [line for line in text.splitlines() if line.strip()]
    if not lines or not lines[0].startswith("QGC WPL 110"):
        raise InteropError('not a waypoint file: the first line must be "QGC WPL 110"')
    home = None
    items = []
    for n, line in enumerate(lines[1:], start=2):
        parts = line.split("\t") if "\t" in line else line.split()
        if len(parts) != 12:
            raise InteropError(f"line {n} has {len(parts)} fields; a waypoint line has 12")
        try:
            index, _current, frame, command = (int(v) for v in parts[:4])
            numbers = [float(v) for v in parts[4:11]]
            autocontinue = bool(int(float(parts[11])))
        except ValueError:
            raise InteropError(f"line {n}: a field is not a number") from None
        if index == 0:
            home = (numbers[4], numbers[5], numbers[6])
            continue
        items.append(_params_to_item(command, frame, numbers, autocontinue))
    return home, items


# -- GeoJSON and KML -----------------------------------------------------------------------


def mission_path_geojson(items: Sequence[MissionItem]) -> dict[str, Any]:
    """The mission's positions as a GeoJSON LineString ([lon, lat, alt])."""
    coordinates = [
        [item.lon, item.lat, item.alt]
        for item in items
        if item.frame != _POSITIONLESS_FRAME and (item.lat or item.lon)
    ]
    return {
        "type": "Feature",
        "properties": {},
        "geometry": {"type": "LineString", "coordinates": coordinates},
    }


def read_geojson_polygon(text: str | bytes, max_vertices: int | None = None) -> dict[str, Any]:
    """A Polygon from a GeoJSON geometry, Feature or FeatureCollection (its first)."""
    try:
        document = json.loads(text)
    except (ValueError, RecursionError) as error:
        raise InteropError(f"not GeoJSON: {error}") from None
    while isinstance(document, dict):
        kind = document.get("type")
        if kind == "Polygon":
            rings = document.get("coordinates")
            if isinstance(rings, list):
                _check_vertices(sum(len(r) for r in rings if isinstance(r, list)), max_vertices)
            return {"type": "Polygon", "coordinates": rings}
        if kind == "Feature":
            document = document.get("geometry")
        elif kind == "FeatureCollection" and document.get("features"):
            document = document["features"][0]
        else:
            break
    raise InteropError("the GeoJSON holds no Polygon")


def read_kml_polygon(data: str | bytes, max_vertices: int | None = None) -> dict[str, Any]:
    """The first Polygon of a KML file (Google Earth), holes included, as GeoJSON."""
    raw = data.encode() if isinstance(data, str) else data
    if len(raw) > MAX_FILE_BYTES:
        raise InteropError(f"the file is larger than {MAX_FILE_BYTES // 1_000_000} MB")
    try:
        root = _parse_xml_without_entities(raw)
    except ElementTree.ParseError as error:
        raise InteropError(f"not a KML file: {error}") from None
    polygon = _first(root, "Polygon")
    if polygon is None:
        raise InteropError("the KML file holds no Polygon")

    def triples(boundary: ElementTree.Element) -> list[str]:
        node = _first(boundary, "coordinates")
        return ("" if node is None else (node.text or "")).split()

    def ring(found: list[str], what: str) -> list[list[float]]:
        if not found:
            raise InteropError(f"the KML polygon's {what} has no coordinates")
        points = []
        for k, triple in enumerate(found):
            try:
                values = [float(v) for v in triple.split(",")]
            except ValueError:
                raise InteropError(f"the {what}'s point {k + 1} is not lon,lat[,alt]") from None
            points.append(values[:2])
        if points[0] != points[-1]:
            points.append(points[0])
        return points

    outer = _first(polygon, "outerBoundaryIs")
    if outer is None:
        raise InteropError("the KML polygon has no outerBoundaryIs")
    inners = [e for e in polygon.iter() if e.tag in (f"{_KML}innerBoundaryIs", "innerBoundaryIs")]
    found = [triples(outer), *(triples(inner) for inner in inners)]
    # Counted before any coordinate is parsed: a huge ring is refused at its size.
    _check_vertices(sum(len(points) for points in found), max_vertices)
    rings = [ring(found[0], "outline")]
    for k, points in enumerate(found[1:]):
        rings.append(ring(points, f"hole {k + 1}"))
    return {"type": "Polygon", "coordinates": rings}


def _refuse_entities(*_: object) -> None:
    raise InteropError("the KML file declares entities; a KML file has none (refused unread)")


def _parse_xml_without_entities(raw: bytes) -> ElementTree.Element:
    """The document's root. The standard library's parser fetches no external entities,
    and expat (>= 2.4) stops a billion laughs, but it still expands what stays under its
    100x amplification limit: 5 MB of KML could become 500 MB. KML has no use for
    entities, so a first pass refuses any declaration as it is read (what defusedxml
    does), before the tree is built."""
    scan = expat.ParserCreate()
    scan.EntityDeclHandler = _refuse_entities
    scan.UnparsedEntityDeclHandler = _refuse_entities
    try:
        scan.Parse(raw, True)
    except expat.ExpatError as error:
        raise InteropError(f"not a KML file: {error}") from None
    return ElementTree.fromstring(raw)


def _first(node: ElementTree.Element, tag: str) -> ElementTree.Element | None:
    """The first element named `tag`, in KML's namespace or none."""
    return next((e for e in node.iter() if e.tag in (f"{_KML}{tag}", tag)), None)
