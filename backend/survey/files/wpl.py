"""`QGC WPL 110` waypoint files (Mission Planner, MAVProxy), written for a drone's survey
mission. The hub reads none: tests read ours back with pymavlink's own reader (mavwp)."""

from __future__ import annotations

from collections.abc import Sequence

from backend.survey.files.items import item_params
from protocol.messages import MissionItem

WPL_HEADER = "QGC WPL 110"


def to_wpl(items: Sequence[MissionItem], home: tuple[float, float, float]) -> str:
    """Line 0 is home (absolute altitude), then one line per item, tab-separated: index,
    current, frame, command, param1-4, x/lat, y/lon, z/alt, autocontinue."""
    lines = [WPL_HEADER]
    lat, lon, alt = home
    lines.append(f"0\t1\t0\t16\t0\t0\t0\t0\t{lat:.8f}\t{lon:.8f}\t{alt:.6f}\t1")
    for number, item in enumerate(items, start=1):
        p = item_params(item)
        fields = [number, 0, item.frame, item.command, *p, int(item.autocontinue)]
        lines.append("\t".join(_wpl_number(v) for v in fields))
    return "\n".join(lines) + "\n"


def _wpl_number(value: float | int | None) -> str:
    if value is None:
        return "nan"  # unset, as QGC and MAVProxy write NaN
    if isinstance(value, int):
        return str(value)
    return f"{value:.8f}".rstrip("0").rstrip(".") or "0"
