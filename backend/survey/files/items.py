"""What every mission file shares: the errors a reader raises, the size limit, and a
mission item to and from its seven params as QGC and MAVLink lay them out.

Pure: every reader raises InteropError with a message saying what is wrong and where.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from protocol.messages import MissionItem

MAX_FILE_BYTES = 5_000_000
# Commands whose params 5-7 are a position; for the others they are plain numbers, which
# MISSION_ITEM_INT carries unscaled in x and y (our MissionItem holds x as lat * 1e7).
POSITIONLESS_FRAME = mavlink2.MAV_FRAME_MISSION


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


def check_vertices(count: int, limit: int | None) -> None:
    if limit is not None and count > limit:
        raise TooManyVertices(count, limit)


def json_number(value: Any, where: str) -> float:
    if value is None:
        return math.nan  # QGC writes NaN as null
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise InteropError(f"{where} must be a number, not {value!r}")
    return float(value)


def params_to_item(
    command: int, frame: int, params: Sequence[float], autocontinue: bool
) -> MissionItem:
    # QGC's null (NaN) is "unset": kept as null for params 1-4 (the mission rules say where
    # a command allows it), refused for a position, never read as 0 (a yaw north, 0 m AMSL).
    for index, name in ((4, "latitude"), (5, "longitude"), (6, "altitude")):
        if math.isnan(params[index]):
            raise ValueError(f"param {index + 1} ({name}) is empty (null)")
    p = list(params)
    if frame == POSITIONLESS_FRAME:
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


def item_params(item: MissionItem) -> list[float | None]:
    if item.frame == POSITIONLESS_FRAME:
        five, six = float(round(item.lat * 1e7)), float(round(item.lon * 1e7))
    else:
        five, six = item.lat, item.lon
    return [item.param1, item.param2, item.param3, item.param4, five, six, item.alt]


def check_size(length: int) -> None:
    if length > MAX_FILE_BYTES:
        raise InteropError(f"the file is larger than {MAX_FILE_BYTES // 1_000_000} MB")
