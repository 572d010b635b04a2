"""QGroundControl's `.plan`: our missions written as simple items, a plan's simple items
read back, and the first Survey complex item read as a survey request (qgc_survey.py)."""

from __future__ import annotations

import json
from collections.abc import Sequence
from typing import Any

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from backend.survey.files.items import (
    POSITIONLESS_FRAME,
    InteropError,
    check_size,
    check_vertices,
    item_params,
    json_number,
    params_to_item,
)
from backend.survey.files.qgc_survey import survey_fields
from protocol.messages import MissionItem


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
            "params": item_params(item),
        }
        if item.frame != POSITIONLESS_FRAME:
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
    check_size(len(text))
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
        numbers = [json_number(p, f"{where} param {k + 1}") for k, p in enumerate(params)]
        try:
            items.append(
                params_to_item(
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
            check_vertices(len(polygon) if isinstance(polygon, list) else 0, max_vertices)
            return survey_fields(raw, f"mission item {i + 1}")
    raise InteropError("the plan has no Survey complex item")
