"""Commands (hub -> agent, and the body of the REST command endpoint): each command, the
unions a client and the hub may send, the request that carries one and the outcome that
answers it."""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import BeforeValidator, Discriminator, Field, model_validator

from protocol.messages.base import (
    MAX_COMMAND_TIMEOUT_S,
    MAX_MISSION_ITEMS,
    MAX_NAME_CHARS,
    MAX_PARAMS,
    Boolean,
    Message,
    MessageText,
    Number,
    RequestId,
)
from protocol.messages.missions import (
    MissionClearCommand,
    MissionDownloadCommand,
    MissionItem,
    MissionSetCurrentCommand,
    MissionUploadCommand,
)
from protocol.messages.params import (
    ParamFix,
    ParamGetCommand,
    ParamListCommand,
    ParamMeta,
    ParamSetCommand,
)


class ArmCommand(Message):
    name: Literal["arm"] = "arm"


class DisarmCommand(Message):
    name: Literal["disarm"] = "disarm"
    force: Boolean = Field(default=False, description="Disarm even in flight (motors stop).")


class TakeoffCommand(Message):
    """Guided take-off: switches to the guided mode and arms first if needed, as QGC does."""

    name: Literal["takeoff"] = "takeoff"
    altitude: Number = Field(gt=0.5, le=500, description="Metres above home.")


class LandCommand(Message):
    name: Literal["land"] = "land"


class ReturnToLaunchCommand(Message):
    name: Literal["rtl"] = "rtl"


class SetModeCommand(Message):
    name: Literal["set_mode"] = "set_mode"
    mode: str = Field(
        min_length=1, max_length=MAX_NAME_CHARS, description="A mode name the vehicle lists."
    )


class GotoCommand(Message):
    name: Literal["goto"] = "goto"
    lat: Number = Field(ge=-90, le=90)
    lon: Number = Field(ge=-180, le=180)
    altitude: Number = Field(gt=0.5, le=500, description="Metres above home.")


class HoldCommand(Message):
    """Stop and hold position (the vehicle type's loiter/hold mode), never blocked."""

    name: Literal["hold"] = "hold"


class ChangeSpeedCommand(Message):
    name: Literal["change_speed"] = "change_speed"
    speed: Number = Field(gt=0, le=50, description="m/s")
    speed_type: Literal["ground", "air"] = "ground"


class SetHomeCommand(Message):
    """Set home (the RTL destination) to the vehicle's position, or to a given point."""

    name: Literal["set_home"] = "set_home"
    use_current: Boolean = True
    lat: Number | None = Field(default=None, ge=-90, le=90)
    lon: Number | None = Field(default=None, ge=-180, le=180)
    alt_msl: Number | None = Field(default=None, ge=-1000, le=10000, description="metres AMSL")

    @model_validator(mode="after")
    def _point_given(self) -> SetHomeCommand:
        given = [self.lat is not None, self.lon is not None, self.alt_msl is not None]
        if self.use_current and any(given):
            raise ValueError("give either use_current or lat/lon/alt_msl, not both")
        if not self.use_current and not all(given):
            raise ValueError("lat, lon and alt_msl are required when use_current is false")
        return self


class RebootCommand(Message):
    """Reboot the flight controller (autopilots refuse this while armed)."""

    name: Literal["reboot"] = "reboot"


class ManualStartCommand(Message):
    """Open browser control on the vehicle (the hub sends it when it grants a lease): the
    agent checks that the autopilot will take MANUAL_CONTROL from it (ArduPilot
    MAV_GCS_SYSID/SYSID_MYGCS and RC_OVERRIDE_TIME, PX4 COM_RC_IN_MODE) and switches to
    the pilot mode, which pauses a mission in progress. Refused with the reason
    otherwise. Not for the REST endpoint: a lease comes from the control message."""

    name: Literal["manual_start"] = "manual_start"


class ManualStopCommand(Message):
    """Close browser control (the lease was released): the vehicle holds."""

    name: Literal["manual_stop"] = "manual_stop"


# Every command but the two that come with the manual-control lease.
_NOT_LEASE_COMMANDS = (
    ArmCommand
    | DisarmCommand
    | TakeoffCommand
    | LandCommand
    | ReturnToLaunchCommand
    | SetModeCommand
    | GotoCommand
    | HoldCommand
    | ChangeSpeedCommand
    | SetHomeCommand
    | RebootCommand
    | ParamListCommand
    | ParamGetCommand
    | ParamSetCommand
    | MissionUploadCommand
    | MissionDownloadCommand
    | MissionClearCommand
    | MissionSetCurrentCommand
)

Command = Annotated[
    _NOT_LEASE_COMMANDS | ManualStartCommand | ManualStopCommand, Field(discriminator="name")
]

LEASE_COMMANDS = frozenset({"manual_start", "manual_stop"})


def lease_only(name: str) -> str:
    """Why a client cannot send ``name`` (one of LEASE_COMMANDS) as a command."""
    return (
        f"{name} comes with the manual-control lease: send a 'control' message on the "
        "live feed (docs/websockets.md)"
    )


def _not_lease_only(value: object) -> object:
    # Said in words: the union's own error would only list the names it takes.
    name = value.get("name") if isinstance(value, dict) else None
    if isinstance(name, str) and name in LEASE_COMMANDS:
        raise ValueError(lease_only(name))
    return value


# What a client may send through the REST API: every command but manual_start and
# manual_stop, which open and close with the manual-control lease (the live feed's
# 'control' message), so the API's schema does not offer them.
ClientCommand = Annotated[
    _NOT_LEASE_COMMANDS,
    # Not Field(discriminator=...): FastAPI lifts a Field out of a body parameter's
    # Annotated, which would leave the validator below outside the tagged union.
    Discriminator("name"),
    BeforeValidator(_not_lease_only),
]


CommandStatus = Literal["accepted", "refused", "timeout", "failed"]


class CommandOutcome(Message):
    """What the flight controller answered, in words an operator can act on."""

    status: CommandStatus
    result: str | None = Field(
        default=None,
        max_length=64,
        description="The MAV_RESULT name from COMMAND_ACK, when there was one.",
    )
    message: MessageText
    values: dict[Annotated[str, Field(max_length=16)], float] | None = Field(
        default=None,
        max_length=MAX_PARAMS,
        description="Parameter values, for the parameter commands.",
    )
    items: list[MissionItem] | None = Field(
        default=None,
        max_length=MAX_MISSION_ITEMS + 1,
        description="The vehicle's mission, for a mission download (home first).",
    )
    fix: ParamFix | None = Field(
        default=None,
        description="A refusal the vehicle's setup causes: the parameter change that "
        "would lift it (e.g. SYSID_MYGCS for manual control)",
    )
    param_meta: ParamMeta | None = Field(
        default=None,
        description="For param_get and param_set: the parameter's metadata, when the "
        "autopilot publishes it (PX4); absent, its range was not checked.",
    )


class CommandRequest(Message):
    type: Literal["command"] = "command"
    request_id: RequestId
    command: Command
    timeout_s: float = Field(
        gt=0, le=MAX_COMMAND_TIMEOUT_S, description="How long the agent may try before giving up."
    )


class CommandResult(Message):
    type: Literal["command_result"] = "command_result"
    request_id: RequestId
    outcome: CommandOutcome
