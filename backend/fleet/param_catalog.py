"""ArduPilot's parameter metadata, which the vehicle does not serve: the hub reads it from
files the operator puts in a folder (``GCS_PARAM_METADATA_DIR``), one per firmware family,
as ArduPilot publishes them (https://autotest.ardupilot.org/Parameters/<family>/apm.pdef.json,
made by Tools/autotest/param_metadata's JSON emitter):

    <folder>/ArduCopter/apm.pdef.json, ArduPlane/..., Rover/..., ArduSub/...

Each file maps groups to parameters, each with ``DisplayName``, ``Description``,
``Units``, ``Range`` (``{"low": "0", "high": "100"}``, as strings) and ``Values``
(``{"0": "Disabled"}``). With a file for the vehicle's family, a write outside its range or
values is refused and answers carry the metadata; without one, nothing is checked and the
API says so (``range_checked`` false). PX4's metadata comes from the vehicle itself,
through its agent.
"""

from __future__ import annotations

import json
import logging
import math
import threading
from pathlib import Path
from typing import Any

from protocol.messages import (
    MAX_PARAM_ENUM_VALUES,
    MAX_PARAM_TEXT_CHARS,
    ParamEnumValue,
    ParamMeta,
)

log = logging.getLogger(__name__)

FILE_NAME = "apm.pdef.json"
# ArduPilot's firmware family for each vehicle type the agent reports.
FAMILIES = {
    "multirotor": "ArduCopter",
    "helicopter": "ArduCopter",
    "fixed_wing": "ArduPlane",
    "rover": "Rover",
    "boat": "Rover",
    "submarine": "ArduSub",
}


def _number(text: object) -> float | None:
    try:
        value = float(str(text))
    except ValueError:
        return None
    return value if math.isfinite(value) else None


def _entry(fields: dict[str, Any]) -> ParamMeta:
    # DisplayName is the short name ("Throttle Failsafe Enable"), Description the sentence
    description = str(fields.get("DisplayName") or fields.get("Description") or "")
    ranged = fields.get("Range") if isinstance(fields.get("Range"), dict) else {}
    values = None
    if isinstance(fields.get("Values"), dict):
        values = [
            ParamEnumValue(value=number, description=str(text)[:MAX_PARAM_TEXT_CHARS])
            for key, text in list(fields["Values"].items())[:MAX_PARAM_ENUM_VALUES]
            if (number := _number(key)) is not None
        ]
    units = str(fields.get("Units") or "")[:32] or None
    return ParamMeta(
        source="file",
        description=description[:MAX_PARAM_TEXT_CHARS],
        units=units,
        min=_number(ranged.get("low")) if ranged else None,
        max=_number(ranged.get("high")) if ranged else None,
        values=values or None,
        reboot_required=str(fields.get("RebootRequired", "")).lower() == "true",
    )


def parse_pdef(document: Any) -> dict[str, ParamMeta]:
    """apm.pdef.json: {"json": {...}, "<group>": {"<PARAM>": {fields}}, ...}."""
    parsed: dict[str, ParamMeta] = {}
    if not isinstance(document, dict):
        raise ValueError("not a JSON object of parameter groups")
    for group, params in document.items():
        if group == "json" or not isinstance(params, dict):
            continue
        for name, fields in params.items():
            if isinstance(name, str) and isinstance(fields, dict):
                parsed[name] = _entry(fields)
    return parsed


class ParamCatalog:
    """The metadata files in ``folder``, each read once, when first needed."""

    def __init__(self, folder: Path | None) -> None:
        self.folder = folder
        self._families: dict[str, dict[str, ParamMeta] | None] = {}
        self._lock = threading.Lock()

    def for_vehicle(self, autopilot: str, vehicle_type: str) -> dict[str, ParamMeta] | None:
        """The vehicle's family's metadata; None: no file for it (nothing is checked)."""
        family = FAMILIES.get(vehicle_type)
        if autopilot != "ardupilot" or family is None or self.folder is None:
            return None
        with self._lock:
            if family not in self._families:
                self._families[family] = self._load(self.folder / family / FILE_NAME)
            return self._families[family]

    def meta(self, autopilot: str, vehicle_type: str, name: str) -> ParamMeta | None:
        catalog = self.for_vehicle(autopilot, vehicle_type)
        return catalog.get(name) if catalog is not None else None

    @staticmethod
    def _load(path: Path) -> dict[str, ParamMeta] | None:
        try:
            with path.open("rb") as source:
                parsed = parse_pdef(json.load(source))
        except FileNotFoundError:
            log.warning("no parameter metadata at %s: writes are not range-checked", path)
            return None
        except (OSError, ValueError) as error:
            log.error(
                "parameter metadata %s unusable (%s): writes are not range-checked", path, error
            )
            return None
        log.info("parameter metadata for %d parameters read from %s", len(parsed), path)
        return parsed
