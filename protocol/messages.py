"""The wire protocol: every message between agent and hub, and between hub and clients.

This module is the single source of truth. The agent and the hub both import it, and
the dashboard's expectations are checked against the JSON schema it exports
(`python -m protocol.messages`). Frames are JSON text, one message per frame, and every
message names its ``type``. The agent announces ``PROTOCOL_VERSION`` in its hello;
the hub refuses a version it does not speak.

Delivery rules per message type (the realtime path honours them):
- ``telemetry`` and ``event``: exactly once in the store. Each carries a per-vehicle
  ``(stream_id, seq)``, counted separately per kind. The agent keeps every frame (on disk
  while the hub is away) until an ``ack`` says it is committed, and replays the rest on
  reconnect; the hub drops duplicates, asks for gaps with ``resend``, and the agent answers
  ``unavailable`` for frames its bounded outbox had to drop.
- ``vehicle`` updates to clients: coalesced; a newer state replaces an unsent one. What
  does not change while an agent stays connected (its modes, autopilot and vehicle type)
  goes out once per client connection, and again only when it changes.
- ``command`` / ``command_result``: request/response, correlated by ``request_id``.
- LIDAR scans are binary frames (`protocol.scans`), the one exception to JSON: agents
  send each scan newest first, then any backlog flagged as replayed; the hub stores them
  all and sends a client only the newest scan of each vehicle it subscribed to
  (``subscribe_scans``), never a queue.
"""

from __future__ import annotations

import json
import sys
from enum import IntEnum
from typing import Annotated, Any, Literal, TypeAlias, TypeVar

from pydantic import (
    AfterValidator,
    BaseModel,
    BeforeValidator,
    ConfigDict,
    Discriminator,
    Field,
    Strict,
    TypeAdapter,
    ValidationError,
    field_validator,
    model_validator,
)
from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from protocol.mavlink_wire import WIRE_RANGES, wire_problem
from protocol.scans import scan_frame_schema

PROTOCOL_VERSION = 1
# Telemetry frames are a few hundred bytes; 64 KiB leaves room for later scan data
# while keeping one misbehaving peer from making the hub buffer megabytes.
MAX_FRAME_BYTES = 64 * 1024

AGENT_WS_PATH = "/api/v1/agent/ws"
CLIENT_WS_PATH = "/api/v1/ws"

T = TypeVar("T")

VehicleId = Annotated[str, Field(pattern=r"^[A-Za-z0-9_.-]{1,64}$", max_length=64)]
StreamId = Annotated[str, Field(min_length=1, max_length=64)]
RequestId = Annotated[str, Field(min_length=1, max_length=64)]

# Every str and list in a message has a bound: one peer must not make the hub store or
# every dashboard receive (a vehicle's modes are in the snapshot every client gets) megabytes.
MAX_NAME_CHARS = 32  # a mode, an autopilot, a vehicle type, a capability
MAX_MODES = 64  # ArduCopter has 27, ArduPlane 25, PX4 about 15
MAX_CAPABILITIES = 32
MAX_MESSAGE_CHARS = 2000  # an outcome's message: the autopilot's reasons included
MAX_PARAMS = 4096  # ArduPilot's largest parameter tables are about 1,800
MAX_MISSION_ITEMS = 2000
MAX_FLEET = 10_000
MAX_COMMAND_TIMEOUT_S = 600.0
Name = Annotated[str, Field(max_length=MAX_NAME_CHARS)]


def _clip(text: object) -> object:
    """Shortens a long explanation rather than losing the answer it belongs to (a refused
    mission lists every item's problem)."""
    if isinstance(text, str) and len(text) > MAX_MESSAGE_CHARS:
        return text[: MAX_MESSAGE_CHARS - 1] + "…"
    return text


MessageText = Annotated[str, BeforeValidator(_clip), Field(max_length=MAX_MESSAGE_CHARS)]


# Numbers and booleans in a request body are JSON's own. FastAPI validates a parsed body in
# pydantic's lax Python mode, which takes `false` for 0, `true` for 1 and "5" for 5: a
# client's type mistake would fly (a battery reserve of `false` is a reserve of 0 %).
# Strict, each is a 422 naming the field. A whole number is still a number.
Number = Annotated[float, Strict()]
Boolean = Annotated[bool, Strict()]


def whole_number(value: object) -> object:
    """JSON has one number type: 3.0 is the integer 3 (JSON Schema's "integer" says so,
    and a client's float arithmetic writes it), so it is taken as 3. A fraction, a bool
    or a string still fails the strict integer after this."""
    if type(value) is float and value.is_integer():
        return int(value)
    return value


# Bounds for an Integer go before the validator, inside one Annotated (as UInt16 has
# them): pydantic would write bounds applied around it into the schema as "ge" and "le",
# which JSON Schema does not know, rather than "minimum" and "maximum".
Integer = Annotated[int, Strict(), BeforeValidator(whole_number)]


def _fits_float32(value: float) -> float:
    problem = wire_problem("float", value)
    if problem is not None:
        raise ValueError(f"{problem}, the MAVLink field's type")
    return value


# Values that go into a MAVLink field of that type, finite and within its range (1e300
# would make pymavlink raise while packing, inside the agent). The bounds are the wire
# type's, from protocol.mavlink_wire; the schema shows them too.
Float32 = Annotated[
    float,
    Strict(),
    Field(
        allow_inf_nan=False,
        json_schema_extra={
            "minimum": WIRE_RANGES["float"][0],
            "maximum": WIRE_RANGES["float"][1],
        },
    ),
    AfterValidator(_fits_float32),
]
UInt16 = Annotated[
    int,
    Strict(),
    Field(ge=WIRE_RANGES["uint16_t"][0], le=WIRE_RANGES["uint16_t"][1]),
    BeforeValidator(whole_number),
]


class CloseCode(IntEnum):
    """WebSocket close codes the hub uses; 4xxx are application-defined."""

    NORMAL = 1000
    POLICY_VIOLATION = 1008  # repeated malformed frames
    MESSAGE_TOO_BIG = 1009
    BAD_HELLO = 4400  # first frame was not a valid hello, or wrong protocol version
    UNAUTHORIZED = 4401  # missing, wrong, expired or revoked credentials
    FORBIDDEN = 4403  # authenticated, but not allowed (role, vehicle, origin)
    # Two aircraft (a cloned SD card, a second agent started by mistake) must never share
    # one vehicle id, so the agent gives up on 4409 and reconnects on 4410.
    VEHICLE_ID_IN_USE = 4409  # another agent, still answering, holds this vehicle id
    SUPERSEDED = 4410  # replaced by the same agent run reconnecting, or this one fell silent
    TOO_SLOW = 4408  # a client feed that stopped reading for longer than the hub waits


# Sequence numbers and times are stored in 64-bit columns; NaN compares false against
# every bound, so it is refused at the edge rather than trusted anywhere.
MAX_SEQ = 2**63 - 1
MAX_UNIX_TIME = 1e11


class Message(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False)


# ---------------------------------------------------------------------------
# Commands (hub -> agent, and the body of the REST command endpoint)
# ---------------------------------------------------------------------------


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
    _NOT_LEASE_COMMANDS | ManualStartCommand | ManualStopCommand,
    Field(discriminator="name"),
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


# ---------------------------------------------------------------------------
# Vehicle state
# ---------------------------------------------------------------------------


# MAV_LANDED_STATE without its UNDEFINED (that is null): in_air, takeoff and landing are
# all airborne.
LandedState = Literal["on_ground", "takeoff", "in_air", "landing"]


class VehicleState(Message):
    """One telemetry snapshot, assembled by the agent from the latest MAVLink messages.
    The hub refuses a snapshot holding a physically impossible value (STATE_BOUNDS:
    latitude beyond ±90, an altitude of 1e308 ...): not stored, not shown, counted."""

    fcu_connected: bool = True
    mode: str = Field(default="UNKNOWN", max_length=MAX_NAME_CHARS)
    armed: bool = False
    system_status: str = Field(default="UNKNOWN", max_length=MAX_NAME_CHARS)
    landed_state: LandedState | None = Field(
        default=None,
        description="Whether it flies: on_ground, or airborne (takeoff, in_air, landing). "
        "Use this, not the altitude (a field above or below home misleads it). Null until "
        "known.",
    )
    landed_state_source: Literal["autopilot", "derived"] | None = Field(
        default=None,
        description="autopilot: EXTENDED_SYS_STATE.landed_state (ArduCopter, ArduPlane, "
        "PX4); derived: the agent's guess from armed, the altitude above home and the climb "
        "rate, where the autopilot does not say (ArduPilot Rover, old firmware): never "
        "takeoff or landing, and a ground vehicle is always on_ground",
    )
    lat: float | None = None
    lon: float | None = None
    alt_msl: float | None = Field(default=None, description="Metres above mean sea level.")
    alt_rel: float | None = Field(default=None, description="Metres above home.")
    heading_deg: float | None = None
    groundspeed: float | None = Field(default=None, description="m/s")
    climb_rate: float | None = Field(default=None, description="m/s, up is positive")
    vn: float | None = Field(default=None, description="m/s north (GLOBAL_POSITION_INT.vx)")
    ve: float | None = Field(default=None, description="m/s east (GLOBAL_POSITION_INT.vy)")
    roll_deg: float | None = None
    pitch_deg: float | None = None
    battery_voltage: float | None = None
    battery_current: float | None = Field(default=None, description="A")
    battery_remaining: float | None = Field(default=None, description="percent")
    gps_fix: int = Field(
        default=0, ge=0, le=255, description="GPS_FIX_TYPE: 0-1 none, 2 2D, 3 3D, 4+ DGPS/RTK"
    )
    satellites: int | None = Field(default=None, ge=0, le=255)
    ready_to_fly: bool | None = Field(
        default=None,
        description="the autopilot's pre-arm checks and estimator allow a take-off "
        "(EKF_STATUS_REPORT, SYS_STATUS, PreArm texts); null until it has said",
    )
    not_ready_reason: str | None = Field(
        default=None, max_length=500, description="why it is not ready, when it is not"
    )
    home_lat: float | None = None
    home_lon: float | None = None
    home_alt_msl: float | None = None
    mission_current: int | None = Field(
        default=None, description="the mission item being flown (MISSION_CURRENT)"
    )
    mission_total: int | None = None
    position_source: str | None = Field(
        default=None,
        max_length=MAX_NAME_CHARS,
        description="the position source in use, e.g. GPS_RAW_INT or GPS2_RAW (RTK)",
    )
    fcu_receive_errors: int = Field(
        default=0, ge=0, description="garbage bytes and bad frames skipped on the FCU link"
    )
    outbox_pending: int = Field(default=0, ge=0, description="frames not yet stored by the hub")
    outbox_dropped: int = Field(
        default=0, ge=0, description="frames the agent dropped because its outbox was full"
    )


# Where a reported value is physically possible, inclusive, per VehicleState field. An
# agent's sample with a value outside (a latitude of 91, an altitude of 1e308: a broken
# sensor, a decoding bug, a hostile peer) is refused whole by the hub, counted, and never
# stored or shown; the agent's link goes on. Not field constraints of VehicleState: the
# agent builds one from whatever the flight controller says, and must not fail doing so.
STATE_BOUNDS: dict[str, tuple[float, float]] = {
    "lat": (-90.0, 90.0),
    "lon": (-180.0, 180.0),
    "home_lat": (-90.0, 90.0),
    "home_lon": (-180.0, 180.0),
    # metres above mean sea level: the Dead Sea shore is at -430, 100 km is space
    "alt_msl": (-1_000.0, 100_000.0),
    "home_alt_msl": (-1_000.0, 100_000.0),
    # metres above home: a vehicle homed on a summit may fly far below it
    "alt_rel": (-10_000.0, 100_000.0),
    "heading_deg": (-360.0, 360.0),
    "roll_deg": (-180.0, 180.0),
    "pitch_deg": (-180.0, 180.0),
    # m/s: 500 is beyond any vehicle this station flies (about Mach 1.5)
    "groundspeed": (0.0, 500.0),
    "climb_rate": (-500.0, 500.0),
    "vn": (-500.0, 500.0),
    "ve": (-500.0, 500.0),
    "battery_voltage": (0.0, 1_000.0),  # V
    "battery_current": (-1_000.0, 1_000.0),  # A; negative while charging
    "battery_remaining": (0.0, 100.0),  # percent
}


def state_out_of_range(state: VehicleState) -> list[tuple[str, str]]:
    """Each field of ``state`` outside STATE_BOUNDS, with the problem said ("lat 91 is
    outside -90..90"); empty for a possible state. None is unknown, not out of range;
    non-finite numbers never get this far (the frame's parse refuses them)."""
    problems = []
    for name, (low, high) in STATE_BOUNDS.items():
        value = getattr(state, name)
        if value is not None and not low <= value <= high:
            problems.append((name, f"{name} {value:g} is outside {low:g}..{high:g}"))
    return problems


# ---------------------------------------------------------------------------
# Agent <-> hub
# ---------------------------------------------------------------------------


class Hello(Message):
    """First frame from an agent: who it is and what it can do."""

    type: Literal["hello"] = "hello"
    protocol: int
    vehicle_id: VehicleId
    autopilot: Name = Field(description="ardupilot, px4 or generic")
    vehicle_type: Name = Field(description="multirotor, rover, fixed_wing, ...")
    system_id: int = Field(ge=1, le=255)
    modes: list[Name] = Field(
        default_factory=list, max_length=MAX_MODES, description="Mode names set_mode accepts."
    )
    capabilities: list[Name] = Field(default_factory=list, max_length=MAX_CAPABILITIES)
    agent_version: Name
    stream_id: StreamId = Field(
        description="Names this agent run's sequence counters, and the run itself: a new "
        "hello from the same run replaces its stale connection, one from another run is "
        "refused while the first still answers (close 4409)."
    )


ReplayedStream = Annotated[
    StreamId | None,
    Field(
        default=None,
        description="Set only on a frame replayed from an earlier agent run: that run's stream.",
    ),
]


class Telemetry(Message):
    type: Literal["telemetry"] = "telemetry"
    stream_id: ReplayedStream = None
    seq: int = Field(ge=0, le=MAX_SEQ)
    time: float = Field(ge=0, le=MAX_UNIX_TIME, description="Unix time of the snapshot, seconds.")
    state: VehicleState


class LiveState(Message):
    """The vehicle's state now, ahead of a backlog being replayed: for the live view only,
    never stored. While an agent catches up after an outage its numbered telemetry is
    minutes old; this keeps the map showing where the vehicle is, not where it was."""

    type: Literal["live_state"] = "live_state"
    time: float = Field(ge=0, le=MAX_UNIX_TIME, description="Unix time of the snapshot, seconds.")
    state: VehicleState


MAX_SOURCE_COUNTS = 32


class ScanSourceStats(Message):
    """The agent's scan source (its LIDAR's parser): what it decoded and what it threw
    away, by reason, since the agent started. Sent when the counts change, every few
    seconds at most; the hub shows the latest in the vehicle's scan diagnostics (never
    stored), so an empty scan comes with a reason."""

    type: Literal["scan_source_stats"] = "scan_source_stats"
    source: Name = Field(description="the LIDAR model (rplidar-a1, ld06, ...), mavlink or ros2")
    counts: dict[Name, Annotated[int, Field(ge=0, le=2**53)]] = Field(
        max_length=MAX_SOURCE_COUNTS,
        description="packets, points, responses, and dropped_<reason> (bad_checksum, "
        "noise_bytes, ...) for a serial LIDAR; each source's own counters otherwise",
    )


EventKind = Literal[
    "statustext",
    "mode",
    "armed",
    "disarmed",
    "link_up",
    "link_down",
    "failsafe",
    "mission",
    "id_clash",  # the hub refused a second agent for this vehicle id (never sent by agents)
    "manual",  # browser manual control started, ended or held by the deadman
    "upload",  # the agent's onboard .tlog could not be handed over (or was, after failing)
    "camera",  # the camera fired (CAMERA_FEEDBACK; PX4: CAMERA_TRIGGER); its photo says where
    "formation",  # a follower joined, held, backed off or left its formation
]
# The kinds the hub itself records in a vehicle's flight log, beside its agent's.
HubEventKind = Literal[
    "command",  # a command sent to the vehicle, with its answer
    "data_lost",  # samples or events the agent no longer had, or the hub refused
    "agent_restart",  # the vehicle's agent came back as a new process
    "obstacle",  # the LIDAR map found an obstacle on the vehicle's path
    "id_clash",
    "link_up",
    "link_down",
    "manual",
]
StoredEventKind = Literal[EventKind, HubEventKind]  # one flat list (typing flattens it)


class Photo(Message):
    """Where and when a photo was taken, as the autopilot reports it (ArduPilot's
    CAMERA_FEEDBACK; PX4's CAMERA_TRIGGER, posed from the streams at its arrival)."""

    index: int = Field(ge=0, le=2**32 - 1, description="the camera's image number (img_idx)")
    lat: float = Field(ge=-90, le=90)
    lon: float = Field(ge=-180, le=180)
    alt_rel: float = Field(ge=-1000, le=10000, description="metres above home")


class Event(Message):
    """Something that happened, for the flight log: a STATUSTEXT, a failsafe, ...

    Events are stored like telemetry (at least once, de-duplicated by ``(stream_id, seq)``),
    with their own sequence numbers."""

    type: Literal["event"] = "event"
    stream_id: ReplayedStream = None
    seq: int = Field(ge=0, le=MAX_SEQ)
    time: float = Field(ge=0, le=MAX_UNIX_TIME, description="Unix time, seconds.")
    kind: EventKind
    severity: int | None = Field(
        default=None, ge=0, le=7, description="MAV_SEVERITY: 0 emergency .. 7 debug"
    )
    text: str = Field(max_length=500)
    mission_item: int | None = Field(
        default=None,
        ge=0,
        le=65535,
        description="the mission item a 'mission' event is about (numbered as the hub does)",
    )
    photo: Photo | None = Field(default=None, description="for a 'camera' event: the photo")


SequencedKind = Literal["telemetry", "event"]


class Unavailable(Message):
    """The agent's answer to a resend it cannot serve: those frames were dropped when its
    outbox was full. The hub records the loss and stops waiting for them."""

    type: Literal["unavailable"] = "unavailable"
    stream_id: StreamId
    kind: SequencedKind
    first_seq: int = Field(ge=0, le=MAX_SEQ)
    last_seq: int = Field(ge=0, le=MAX_SEQ)
    reason: str = Field(max_length=200)


class CommandResult(Message):
    type: Literal["command_result"] = "command_result"
    request_id: RequestId
    outcome: CommandOutcome


class Welcome(Message):
    type: Literal["welcome"] = "welcome"
    protocol: int = PROTOCOL_VERSION
    vehicle_id: VehicleId


class CommandRequest(Message):
    type: Literal["command"] = "command"
    request_id: RequestId
    command: Command
    timeout_s: float = Field(
        gt=0, le=MAX_COMMAND_TIMEOUT_S, description="How long the agent may try before giving up."
    )


class Ack(Message):
    """Everything up to these sequence numbers of the stream is stored; the agent may
    forget it. Sent after the database commit, never on receipt."""

    type: Literal["ack"] = "ack"
    stream_id: StreamId
    telemetry_seq: int | None = Field(default=None, ge=0, le=MAX_SEQ)
    event_seq: int | None = Field(default=None, ge=0, le=MAX_SEQ)


class Resend(Message):
    """The hub saw a gap in a stream: send these frames again (or say they are gone)."""

    type: Literal["resend"] = "resend"
    stream_id: StreamId
    kind: SequencedKind
    first_seq: int = Field(ge=0, le=MAX_SEQ)
    last_seq: int = Field(ge=0, le=MAX_SEQ)


class ErrorReply(Message):
    """Sent to a peer whose frame could not be used; the connection stays open."""

    type: Literal["error"] = "error"
    code: Literal[
        "bad_frame", "invalid_message", "unexpected_message", "too_many_errors", "forbidden"
    ]
    message: MessageText


# ---------------------------------------------------------------------------
# Hub <-> clients (dashboard, integrations)
# ---------------------------------------------------------------------------


class VehicleSummary(Message):
    id: VehicleId
    autopilot: Name
    vehicle_type: Name
    modes: list[Name] = Field(max_length=MAX_MODES)
    connected: bool
    last_seen: float | None = Field(default=None, description="Unix time of the last telemetry.")
    state: VehicleState | None = None


def _unchanged(value: object) -> bool:
    return value is None


# What a vehicle's agent says once, in its hello, and what therefore does not change while
# it stays connected: a live update leaves it out unless it changed.
_SAID_ONCE = (
    "Left out when this feed has already sent it and it has not changed since: keep the "
    "value from the fleet snapshot or an earlier update."
)
_SAID_ONCE_FIELDS = ("autopilot", "vehicle_type", "modes")


def _said_once_schema(schema: dict[str, Any]) -> None:
    """On the wire these fields are a value or absent, never null: say so in the schema
    (the dashboard's types are generated from it)."""
    for name in _SAID_ONCE_FIELDS:
        field = schema["properties"][name]
        del field["default"]
        field.update(next(kind for kind in field.pop("anyOf") if kind.get("type") != "null"))


class VehicleChange(Message):
    """One vehicle's live update. It carries ``autopilot``, ``vehicle_type`` and ``modes``
    (a third of the frame, ten times a second) only the first time this connection shows
    the vehicle and when they change (its agent reconnected with another hello, or sent
    the autopilot's own mode list); the fleet
    snapshot a new connection starts with always has them."""

    model_config = ConfigDict(json_schema_extra=_said_once_schema)

    id: VehicleId
    autopilot: Name | None = Field(default=None, exclude_if=_unchanged, description=_SAID_ONCE)
    vehicle_type: Name | None = Field(default=None, exclude_if=_unchanged, description=_SAID_ONCE)
    modes: list[Name] | None = Field(
        default=None, max_length=MAX_MODES, exclude_if=_unchanged, description=_SAID_ONCE
    )
    connected: bool
    last_seen: float | None = Field(default=None, description="Unix time of the last telemetry.")
    state: VehicleState | None = None


class FleetSnapshot(Message):
    type: Literal["fleet"] = "fleet"
    vehicles: list[VehicleSummary] = Field(max_length=MAX_FLEET)


class VehicleBatch(Message):
    """The vehicles that changed since this connection's last batch, each once (its newest
    state): one frame per tick for the whole fleet, not one per vehicle. A vehicle's state
    goes out at most once per the hub's ``ui_update_interval_s``; a client that reads too
    slowly gets the newest state of each vehicle when it catches up, never a backlog."""

    type: Literal["vehicles"] = "vehicles"
    vehicles: list[VehicleChange] = Field(max_length=MAX_FLEET)


# A batch of live events stays well inside a frame: an event is at most about 800 bytes.
MAX_LIVE_EVENTS = 64


class LiveEvent(Message):
    """An event as the live feed carries it: the agent's (a STATUSTEXT, a mode change, a
    failsafe, ...) or the hub's own (a link up or down, a command's result)."""

    vehicle_id: VehicleId
    time: float = Field(ge=0, le=MAX_UNIX_TIME, description="Unix time, seconds.")
    kind: Name = Field(
        description="an agent's event kind, or one of the hub's: command, data_lost, ..."
    )
    severity: int | None = Field(
        default=None, ge=0, le=7, description="MAV_SEVERITY: 0 emergency .. 7 debug"
    )
    text: str = Field(max_length=500)
    mission_item: int | None = Field(default=None, ge=0, le=65535)
    photo: Photo | None = Field(default=None, description="for a 'camera' event: the photo")
    repeat: int = Field(
        default=1,
        ge=1,
        description="how many identical events (same vehicle, kind, severity and text) "
        "this one stands for: repeats within one batch are sent once; time is the newest",
    )


class EventBatch(Message):
    """The events since the last batch, oldest first: at most one batch every
    GCS_UI_UPDATE_INTERVAL_S. A client that reads too slowly loses the least severe events
    first; ``dropped`` says how many."""

    type: Literal["events"] = "events"
    events: list[LiveEvent] = Field(max_length=MAX_LIVE_EVENTS)
    dropped: int = Field(
        default=0, ge=0, description="events left out since the last batch: the queue was full"
    )


class SubscribeScans(Message):
    """Send me this vehicle's scans (binary frames, protocol/scans.py), newest only."""

    type: Literal["subscribe_scans"] = "subscribe_scans"
    vehicle_id: VehicleId


class UnsubscribeScans(Message):
    type: Literal["unsubscribe_scans"] = "unsubscribe_scans"
    vehicle_id: VehicleId


MAX_SCAN_SUBSCRIPTIONS = 64


class ScanSubscriptions(Message):
    """The vehicles whose scans this feed now receives (the answer to a (un)subscribe)."""

    type: Literal["scan_subscriptions"] = "scan_subscriptions"
    vehicles: list[VehicleId] = Field(max_length=MAX_SCAN_SUBSCRIPTIONS)


MapLayer: TypeAlias = Literal["points", "obstacles"]
MAX_MAP_POINTS = 500_000  # the most the REST point map gives at once
MAX_MAP_POINTS_SENT = 20_000  # the newest voxels of a point_map message
MAX_OBSTACLES_SENT = 1_000


class SubscribeMap(Message):
    """Send me the site's map as it changes: ``points`` (the voxel point map, its newest
    voxels, at most every few seconds) and ``obstacles`` (the clusters found in it, when
    the set changes). The current state comes at once; a slow reader gets the newest."""

    type: Literal["subscribe_map"] = "subscribe_map"
    layers: list[MapLayer] = Field(min_length=1, max_length=2)


class UnsubscribeMap(Message):
    type: Literal["unsubscribe_map"] = "unsubscribe_map"
    layers: list[MapLayer] = Field(min_length=1, max_length=2)


class MapSubscriptions(Message):
    """The map layers this feed now receives (the answer to a (un)subscribe)."""

    type: Literal["map_subscriptions"] = "map_subscriptions"
    layers: list[MapLayer] = Field(max_length=2)


class SiteOrigin(BaseModel):
    """The origin of the site's east/north/up metres (the scans' and the point map's)."""

    lat: float
    lon: float
    alt_msl: float


class Obstacle(BaseModel):
    """A cluster of the point map, above the ground: its extent in site east/north/up
    metres; it keeps its id while it is seen."""

    id: int
    east_min: float
    east_max: float
    north_min: float
    north_max: float
    up_min: float
    up_max: float
    voxels: int
    outline: list[tuple[float, float]] = Field(
        max_length=4, description="the extent's corners as latitude, longitude (degrees)"
    )


class PointMapView(BaseModel):
    site: SiteOrigin | None
    voxel_m: float
    voxels: int = Field(description="voxels in the map (``points`` may hold fewer)")
    evicted: int = Field(description="voxels dropped so far to keep the map in its bound")
    points: list[tuple[float, float, float]] = Field(
        max_length=MAX_MAP_POINTS,
        description="voxel centres, east/north/up metres from the site origin, newest first",
    )


class PointMapUpdate(Message):
    type: Literal["point_map"] = "point_map"
    map: PointMapView


class ObstaclesUpdate(Message):
    type: Literal["obstacles"] = "obstacles"
    site: SiteOrigin | None
    obstacles: list[Obstacle] = Field(max_length=MAX_OBSTACLES_SENT)


class Ping(Message):
    type: Literal["ping"] = "ping"
    nonce: str | None = Field(default=None, max_length=64)


class Pong(Message):
    type: Literal["pong"] = "pong"
    nonce: str | None = Field(default=None, max_length=64)


class ModeList(Message):
    """The vehicle's modes as its autopilot reports them (MAVLink AVAILABLE_MODES: PX4
    from 1.15, ArduPilot from 4.7), sent when the agent has read the list after its hello
    and whenever the autopilot says it changed (AVAILABLE_MODES_MONITOR). It replaces the
    hello's ``modes``, which were the agent's fixed table for the autopilot until then."""

    type: Literal["modes"] = "modes"
    modes: list[Name] = Field(
        max_length=MAX_MODES,
        description="Mode names set_mode accepts, as the autopilot lists them.",
    )


# ---------------------------------------------------------------------------
# Manual control (browser -> hub -> agent)
# ---------------------------------------------------------------------------

# MAVLink MANUAL_CONTROL's ranges: x (pitch, forward +), y (roll, right +) and r (yaw,
# clockwise +) in [-1000, 1000]; z (throttle or climb) in [0, 1000], 500 at mid stick.
StickAxis = Annotated[int, Field(ge=-1000, le=1000)]
ThrottleAxis = Annotated[int, Field(ge=0, le=1000)]


class ManualAxes(Message):
    x: StickAxis = Field(description="pitch: forward positive, -1000..1000")
    y: StickAxis = Field(description="roll: right positive, -1000..1000")
    z: ThrottleAxis = Field(default=500, description="throttle or climb: 0..1000, 500 mid")
    r: StickAxis = Field(default=0, description="yaw: clockwise positive, -1000..1000")
    buttons: int = Field(default=0, ge=0, le=65535, description="MANUAL_CONTROL buttons")


class ControlRequest(Message):
    """Ask for (or give back) the manual-control lease of one vehicle. Needs the
    'command' permission; one pilot per vehicle. An acquire is granted (a `lease` naming
    the holder, to every client) only once the vehicle's agent has checked that the
    autopilot takes MANUAL_CONTROL from it and switched to its pilot mode; otherwise
    a `lease_refused` gives the reason (e.g. SYSID_MYGCS or COM_RC_IN_MODE) and, where
    a parameter is the reason, the change that would lift it. Release and revoke put
    the vehicle in its hold mode."""

    type: Literal["control"] = "control"
    vehicle_id: VehicleId
    action: Literal["acquire", "release", "revoke"] = Field(
        description="revoke: an admin ends whoever's lease"
    )


# Where a frame's values come from. The agent holds the vehicle when a "gamepad" or
# "program" stream repeats the same off-centre values for its frozen time (a frozen
# device, or a client streaming its last reading); an on-screen stick or a key held
# still is a pilot holding a steady input, and the page's own liveness (hidden, blurred,
# pointer lost) stops those streams.
InputSource = Literal["gamepad", "touch", "keyboard", "program"]


class ManualInput(Message):
    """One frame of stick input, sent by the lease holder at 25 Hz or more. Frames from
    a client without the lease, with a seq not newer than the last, or faster than
    100 Hz are refused and never forwarded; the newest frame wins."""

    type: Literal["manual"] = "manual"
    vehicle_id: VehicleId
    seq: int = Field(ge=0, le=MAX_SEQ)
    axes: ManualAxes
    source: InputSource = Field(
        default="program",
        description="gamepad and program streams that repeat the same off-centre values "
        "for 3 s count as frozen and hold the vehicle; touch and keyboard do not",
    )
    sent_ms: float | None = Field(
        default=None,
        ge=0,
        le=1e15,
        description="the client's own clock when it read the input (ms); the agent "
        "echoes it (manual_echo) so the pilot sees the input-to-vehicle round trip",
    )


class LeaseState(Message):
    """Who flies a vehicle by hand now (holder None: nobody), sent to every client when
    it changes, and for every vehicle with a lease history when a client connects. A
    lease ends when released, revoked by an admin, expired (no input for 2 s), on the
    vehicle (the agent's deadman, frozen input, its hold button, a mode change from the
    RC transmitter or another GCS), or with a hub restart; `reason` says which."""

    type: Literal["lease"] = "lease"
    vehicle_id: VehicleId
    holder: str | None = Field(default=None, max_length=200)
    reason: str = Field(default="", max_length=200)
    resume_mode: str | None = Field(
        default=None,
        max_length=MAX_NAME_CHARS,
        description="a mission was in progress when the lease began and is paused: "
        "set this mode to resume it (ArduPilot AUTO, PX4 MISSION)",
    )


class LeaseRefusal(Message):
    """A `control` request refused, to the client that sent it: the reason in words (the
    autopilot's setup, another pilot, the vehicle offline, ...), and where the vehicle's
    setup is the reason, the parameter change that would lift it. Every dashboard also
    sees the refusal in its event feed (a hub event of kind "control")."""

    type: Literal["lease_refused"] = "lease_refused"
    vehicle_id: VehicleId
    action: Literal["acquire", "release", "revoke"]
    reason: MessageText
    fix: ParamFix | None = None


class ManualFrame(Message):
    """Stick input relayed to the agent; the agent holds the vehicle when these stop."""

    type: Literal["manual"] = "manual"
    seq: int = Field(ge=0, le=MAX_SEQ)
    axes: ManualAxes
    source: InputSource = "program"
    sent_ms: float | None = Field(default=None, ge=0, le=1e15)


class ManualApplied(Message):
    """The agent sent this frame to the flight controller as MANUAL_CONTROL (about twice
    a second while a stream lasts): the hub passes it to the lease holder."""

    type: Literal["manual_applied"] = "manual_applied"
    seq: int = Field(ge=0, le=MAX_SEQ)
    sent_ms: float | None = Field(default=None, ge=0, le=1e15)


class ManualEcho(Message):
    """To the lease holder: its frame ``seq`` went out to the flight controller. Its
    ``sent_ms`` against the client's clock now is the input-to-vehicle round trip."""

    type: Literal["manual_echo"] = "manual_echo"
    vehicle_id: VehicleId
    seq: int = Field(ge=0, le=MAX_SEQ)
    sent_ms: float | None = Field(default=None, ge=0, le=1e15)


class SurveyDroneProgress(Message):
    vehicle_id: VehicleId
    state: Name = Field(description="assigned, flying, done or dropped")
    lanes_done: int = Field(ge=0)
    lanes_total: int = Field(ge=0)
    photos: int = Field(ge=0)
    reason: str | None = Field(default=None, max_length=500, description="why it dropped out")


class SurveyUpdate(Message):
    """An area survey's progress, at most one a second per survey (newest wins): lanes
    flown, photos triggered (CAMERA_FEEDBACK) and the share of the area their footprints
    cover, overall and per drone, and whether a hand-over awaits the operator."""

    type: Literal["survey"] = "survey"
    survey_id: Name
    state: Name = Field(description="planned, flying, handover_offered, done, aborted, failed")
    lanes_done: int = Field(ge=0)
    lanes_total: int = Field(ge=0)
    photos: int = Field(ge=0)
    covered_pct: float = Field(ge=0, le=100)
    drones: list[SurveyDroneProgress] = Field(max_length=64)
    handover_lanes: int | None = Field(
        default=None, ge=0, description="lanes a hand-over offers to move; null if none offered"
    )


FormationId = Annotated[str, Field(pattern=r"^[A-Za-z0-9_.-]{1,64}$", max_length=64)]
_OFFSET_M = 500.0
_LOCAL_M = 100_000.0  # a formation's route stays within 100 km of its first waypoint
_SPEED_MS = 100.0


class GraphEdge(Message):
    """A neighbour in a consensus follower's communication graph: its slot (the same
    axes as the follower's own) and the edge's weight."""

    vehicle_id: VehicleId
    x: float = Field(ge=-_OFFSET_M, le=_OFFSET_M)
    y: float = Field(ge=-_OFFSET_M, le=_OFFSET_M)
    up: float = Field(ge=-_OFFSET_M, le=_OFFSET_M)
    frame: Literal["heading", "ne"] = "heading"
    weight: float = Field(default=1.0, gt=0, le=10)


class FormationSlot(Message):
    """Fly this slot in a formation; sent again with a new offset when the shape or
    spacing changes in flight. Positions in the formation's messages are metres north,
    east and up (above home) on the tangent plane at ``origin``."""

    type: Literal["formation"] = "formation"
    formation_id: FormationId
    origin_lat: float = Field(ge=-90, le=90)
    origin_lon: float = Field(ge=-180, le=180)
    x: float = Field(ge=-_OFFSET_M, le=_OFFSET_M, description="forward (heading) or north")
    y: float = Field(ge=-_OFFSET_M, le=_OFFSET_M, description="right (heading) or east")
    up: float = Field(ge=-_OFFSET_M, le=_OFFSET_M, description="metres above the leader")
    frame: Literal["heading", "ne"] = "heading"
    min_separation_m: float = Field(gt=0, le=100)
    face_heading: bool = Field(
        default=False, description="turn to the leader's heading (a leader flying the route)"
    )
    controller: Literal["leader_follower", "consensus"] = Field(
        default="leader_follower",
        description="leader_follower: position targets around the predicted leader with "
        "its velocity as feed-forward; consensus: velocity targets from the leader's and "
        "the graph neighbours' states",
    )
    k_leader: float = Field(default=1.0, gt=0, le=100, description="consensus: the leader's weight")
    k_neighbour: float = Field(
        default=0.5, ge=0, le=100, description="consensus: each neighbour's weight"
    )
    graph: list[GraphEdge] = Field(
        default_factory=list, max_length=64, description="consensus: this follower's neighbours"
    )
    obstacle_clearance_m: float = Field(
        default=0.0,
        ge=0,
        le=50,
        description="hold short when the slot comes this close to a point of the leader's "
        "scans (0: not checked)",
    )


class FormationEnd(Message):
    """Leave the formation and hold."""

    type: Literal["formation_end"] = "formation_end"
    formation_id: FormationId
    reason: str = Field(default="", max_length=200)


class Neighbour(Message):
    """Another member's last report: for the separation check, and (with its velocity
    and time, to predict it as the leader is) for a consensus follower."""

    vehicle_id: VehicleId
    north: float = Field(ge=-_LOCAL_M, le=_LOCAL_M)
    east: float = Field(ge=-_LOCAL_M, le=_LOCAL_M)
    up: float = Field(ge=-_LOCAL_M, le=_LOCAL_M)
    vn: float = Field(default=0.0, ge=-_SPEED_MS, le=_SPEED_MS)
    ve: float = Field(default=0.0, ge=-_SPEED_MS, le=_SPEED_MS)
    vu: float = Field(default=0.0, ge=-_SPEED_MS, le=_SPEED_MS)
    time: float | None = Field(default=None, ge=0, le=MAX_UNIX_TIME)


class LeaderUpdate(Message):
    """The leader's state relayed to a follower (newest wins), with the other members'
    positions for the separation check. ``time`` is when the leader was there (Unix
    seconds): the follower predicts it forward over the link's delay."""

    type: Literal["leader"] = "leader"
    formation_id: FormationId
    time: float = Field(ge=0, le=MAX_UNIX_TIME)
    north: float = Field(ge=-_LOCAL_M, le=_LOCAL_M)
    east: float = Field(ge=-_LOCAL_M, le=_LOCAL_M)
    up: float = Field(ge=-_LOCAL_M, le=_LOCAL_M)
    vn: float = Field(ge=-_SPEED_MS, le=_SPEED_MS)
    ve: float = Field(ge=-_SPEED_MS, le=_SPEED_MS)
    vu: float = Field(ge=-_SPEED_MS, le=_SPEED_MS)
    heading_deg: float = Field(ge=0, le=360)
    neighbours: list[Neighbour] = Field(default_factory=list, max_length=64)


MAX_SCAN_POINTS = 1024


class LeaderScan(Message):
    """The returns of one of the leader's LIDAR scans, relayed to each follower in the
    formation's frame (metres north and east on its tangent plane), thinned to one per
    cell and at most `MAX_SCAN_POINTS`. A 2-D scan says nothing of height: a follower
    treats each point as an obstacle from the ground up. ``time`` is the scan's (Unix
    seconds), ``seq`` the leader's scan number."""

    type: Literal["leader_scan"] = "leader_scan"
    formation_id: FormationId
    time: float = Field(ge=0, le=MAX_UNIX_TIME)
    seq: int = Field(ge=0)
    north: list[float] = Field(max_length=MAX_SCAN_POINTS)
    east: list[float] = Field(max_length=MAX_SCAN_POINTS)

    @model_validator(mode="after")
    def _paired(self) -> LeaderScan:
        if len(self.north) != len(self.east):
            raise ValueError("north and east must list the same number of points")
        if any(abs(v) > _LOCAL_M for v in (*self.north, *self.east)):
            raise ValueError(f"points must lie within {_LOCAL_M:g} m of the origin")
        return self


# The hub pings an agent to learn whether it is still there (another agent wants its
# vehicle id); the agent answers with a pong.
AgentToHub: TypeAlias = Annotated[
    Hello
    | Telemetry
    | LiveState
    | Event
    | CommandResult
    | Unavailable
    | Pong
    | ManualApplied
    | ScanSourceStats
    | ModeList,
    Field(discriminator="type"),
]
HubToAgent: TypeAlias = Annotated[
    Welcome
    | CommandRequest
    | Ack
    | Resend
    | ErrorReply
    | Ping
    | ManualFrame
    | FormationSlot
    | FormationEnd
    | LeaderUpdate
    | LeaderScan,
    Field(discriminator="type"),
]
ClientToHub: TypeAlias = Annotated[
    Ping
    | ControlRequest
    | ManualInput
    | SubscribeScans
    | UnsubscribeScans
    | SubscribeMap
    | UnsubscribeMap,
    Field(discriminator="type"),
]
HubToClient: TypeAlias = Annotated[
    FleetSnapshot
    | VehicleBatch
    | EventBatch
    | ScanSubscriptions
    | Pong
    | ErrorReply
    | LeaseState
    | LeaseRefusal
    | SurveyUpdate
    | ManualEcho
    | MapSubscriptions
    | PointMapUpdate
    | ObstaclesUpdate,
    Field(discriminator="type"),
]

agent_to_hub: TypeAdapter[AgentToHub] = TypeAdapter(AgentToHub)
hub_to_agent: TypeAdapter[HubToAgent] = TypeAdapter(HubToAgent)
client_to_hub: TypeAdapter[ClientToHub] = TypeAdapter(ClientToHub)
hub_to_client: TypeAdapter[HubToClient] = TypeAdapter(HubToClient)
command_adapter: TypeAdapter[Command] = TypeAdapter(Command)


class ProtocolError(ValueError):
    """A frame that does not parse or validate; ``code`` goes into the ErrorReply."""

    def __init__(self, code: Literal["bad_frame", "invalid_message"], message: str) -> None:
        super().__init__(message)
        self.code = code
        self.message = message

    def reply(self) -> ErrorReply:
        return ErrorReply(code=self.code, message=self.message)


def describe_validation_error(error: ValidationError) -> str:
    """Name each offending field, e.g. ``state.lat: Input should be a valid number``."""
    parts = []
    for item in error.errors(include_url=False):
        location = ".".join(str(part) for part in item["loc"]) or "(message)"
        parts.append(f"{location}: {item['msg']}")
    return "; ".join(parts)


def decode(adapter: TypeAdapter[T], frame: str | bytes) -> T:
    """Parse one frame, raising ProtocolError with a message that names the problem.

    A valid frame is parsed and validated in one pass (pydantic-core's own JSON parser:
    half the time of json.loads, then validation, on a telemetry frame). A frame it
    refuses takes the path below, which names the problem as it always has."""
    try:
        return adapter.validate_json(frame)
    except ValidationError:
        pass
    try:
        raw = json.loads(frame)
    except (ValueError, RecursionError) as error:
        # ValueError covers JSONDecodeError, UnicodeDecodeError and an integer over the
        # interpreter's digit limit; RecursionError, nesting deeper than the parser goes.
        raise ProtocolError("bad_frame", f"frame is not valid JSON: {error}") from None
    if not isinstance(raw, dict) or "type" not in raw:
        raise ProtocolError("invalid_message", "frame must be a JSON object with a 'type' field")
    try:
        return adapter.validate_python(raw)
    except ValidationError as error:
        raise ProtocolError("invalid_message", describe_validation_error(error)) from None


def encode(message: Message) -> str:
    return message.model_dump_json()


def json_schema() -> dict[str, Any]:
    """Everything a client needs to check its types against."""
    return {
        "protocol": PROTOCOL_VERSION,
        "agent_to_hub": agent_to_hub.json_schema(),
        "hub_to_agent": hub_to_agent.json_schema(),
        "client_to_hub": client_to_hub.json_schema(),
        "hub_to_client": hub_to_client.json_schema(),
        # LIDAR scans: binary WebSocket frames, not JSON (protocol/scans.py)
        "scan_frame": scan_frame_schema(),
    }


if __name__ == "__main__":
    json.dump(json_schema(), sys.stdout, indent=2)
    sys.stdout.write("\n")
