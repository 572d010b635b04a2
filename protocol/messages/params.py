"""Parameters: the commands that read and write them, what one means (its metadata), and
the change that would lift a refusal."""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import Field

from protocol.messages.base import Float32, Message

ParamName = Annotated[
    str, Field(pattern=r"^[A-Z0-9_]{1,16}$", max_length=16, description="e.g. WPNAV_SPEED")
]


class ParamListCommand(Message):
    """Read every parameter (the flight controller's whole table)."""

    name: Literal["param_list"] = "param_list"


class ParamGetCommand(Message):
    name: Literal["param_get"] = "param_get"
    param: ParamName


class ParamSetCommand(Message):
    """Set one parameter; accepted only when the flight controller echoes the new value."""

    name: Literal["param_set"] = "param_set"
    param: ParamName
    value: Float32 = Field(description="PARAM_SET.param_value is a float32")


class ParamFix(Message):
    """The parameter change that would let a refused request through, as the refusal's
    words say it: for a client to offer to whoever may make it (an admin, where the
    parameter is safety-critical), never to apply by itself."""

    param: ParamName
    value: Float32


MAX_PARAM_ENUM_VALUES = 64
MAX_PARAM_TEXT_CHARS = 500


class ParamEnumValue(Message):
    value: float
    description: str = Field(max_length=MAX_PARAM_TEXT_CHARS)


class ParamMeta(Message):
    """What a parameter means, from the autopilot's own metadata (PX4's, over its component
    metadata protocol) or the hub's file for the firmware (ArduPilot's apm.pdef.json): its
    range, the values it takes, its units and description. A write outside the range or
    the values is refused."""

    source: Literal["autopilot", "file"] = Field(
        default="autopilot",
        description="where it came from: the autopilot's own metadata (PX4), or the "
        "hub's metadata file for the firmware family (ArduPilot's apm.pdef.json)",
    )
    description: str = Field(default="", max_length=MAX_PARAM_TEXT_CHARS)
    units: str | None = Field(default=None, max_length=32)
    min: float | None = None
    max: float | None = None
    values: list[ParamEnumValue] | None = Field(
        default=None, max_length=MAX_PARAM_ENUM_VALUES, description="the values it takes"
    )
    reboot_required: bool = False
