"""Missions: one item as MISSION_ITEM_INT carries it, and the commands that upload,
download, clear and step a mission."""

from __future__ import annotations

from typing import Literal

from pydantic import Field, field_validator
from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from protocol.messages.base import (
    MAX_MISSION_ITEMS,
    Boolean,
    Float32,
    Integer,
    Message,
    Number,
    UInt16,
)

# MISSION_ITEM_INT carries integer positions whatever its frame says, so the "_INT" frames
# add nothing there (MAVLink deprecates them), and autopilots do not keep them: ArduPilot
# stores "relative altitude" and gives back 3 for an item sent as 6, PX4 gives back 6 for
# one sent as 3. One form on both sides of the hub, so a round trip returns what was sent.
_PLAIN_FRAME: dict[int, int] = {
    mavlink2.MAV_FRAME_GLOBAL_INT: mavlink2.MAV_FRAME_GLOBAL,
    mavlink2.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT: mavlink2.MAV_FRAME_GLOBAL_RELATIVE_ALT,
    mavlink2.MAV_FRAME_GLOBAL_TERRAIN_ALT_INT: mavlink2.MAV_FRAME_GLOBAL_TERRAIN_ALT,
}


_UNSET_PARAM = (
    "null for unset (NaN in MAVLink), where the command's spec allows NaN or calls the "
    "parameter empty (e.g. a waypoint's param4 yaw: keep the heading mode)"
)


class MissionItem(Message):
    """One mission item, as MISSION_ITEM_INT carries it (positions in degrees)."""

    command: UInt16 = Field(description="MAV_CMD number, e.g. 16 NAV_WAYPOINT")
    frame: Integer = Field(
        default=mavlink2.MAV_FRAME_GLOBAL_RELATIVE_ALT,
        ge=0,
        le=21,
        description="MAV_FRAME: 0 above sea level, 3 above home, 10 above terrain. The _INT "
        "forms 5, 6 and 11 are accepted and become 0, 3 and 10, in uploads and downloads "
        "alike. A command without a position ignores its frame (ArduPilot gives back 0).",
    )
    # null is MAVLink's NaN, "unset" (a yaw of NaN keeps the heading mode): sent as NaN and
    # read back as null. The mission rules take it only where the command's spec gives NaN
    # a meaning or calls the parameter empty; never 0, which would be a value (north).
    param1: Float32 | None = Field(default=0.0, description=_UNSET_PARAM)
    param2: Float32 | None = Field(default=0.0, description=_UNSET_PARAM)
    param3: Float32 | None = Field(default=0.0, description=_UNSET_PARAM)
    param4: Float32 | None = Field(default=0.0, description=_UNSET_PARAM)
    lat: Number = Field(default=0.0, ge=-90, le=90)
    lon: Number = Field(default=0.0, ge=-180, le=180)
    alt: Number = Field(default=0.0, ge=-1000, le=10000, description="metres (a float32)")
    autocontinue: Boolean = True

    @field_validator("frame")
    @classmethod
    def _plain_frame(cls, frame: int) -> int:
        return _PLAIN_FRAME.get(frame, frame)


class MissionUploadCommand(Message):
    """Replace the vehicle's mission (item 0, home, is added by the agent)."""

    name: Literal["mission_upload"] = "mission_upload"
    items: list[MissionItem] = Field(min_length=1, max_length=MAX_MISSION_ITEMS)


class MissionDownloadCommand(Message):
    name: Literal["mission_download"] = "mission_download"


class MissionClearCommand(Message):
    name: Literal["mission_clear"] = "mission_clear"


class MissionSetCurrentCommand(Message):
    name: Literal["mission_set_current"] = "mission_set_current"
    seq: Integer = Field(ge=1, le=MAX_MISSION_ITEMS, description="1 is the first item after home")
