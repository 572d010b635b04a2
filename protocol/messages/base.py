"""The wire's foundations: its version, paths and frame size, the bounded value types
every message is built from, and the `Message` base (frozen, no extra fields, no NaN)."""

from __future__ import annotations

from typing import Annotated

from pydantic import AfterValidator, BaseModel, BeforeValidator, ConfigDict, Field, Strict

from protocol.mavlink_wire import WIRE_RANGES, wire_problem

PROTOCOL_VERSION = 1
# Telemetry frames are a few hundred bytes; 64 KiB leaves room for later scan data
# while keeping one misbehaving peer from making the hub buffer megabytes.
MAX_FRAME_BYTES = 64 * 1024

AGENT_WS_PATH = "/api/v1/agent/ws"
CLIENT_WS_PATH = "/api/v1/ws"


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
        json_schema_extra={"minimum": WIRE_RANGES["float"][0], "maximum": WIRE_RANGES["float"][1]},
    ),
    AfterValidator(_fits_float32),
]
UInt16 = Annotated[
    int,
    Strict(),
    Field(ge=WIRE_RANGES["uint16_t"][0], le=WIRE_RANGES["uint16_t"][1]),
    BeforeValidator(whole_number),
]


# Sequence numbers and times are stored in 64-bit columns; NaN compares false against
# every bound, so it is refused at the edge rather than trusted anywhere.
MAX_SEQ = 2**63 - 1
MAX_UNIX_TIME = 1e11


class Message(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False)
