"""How a parameter's value travels in PARAM_VALUE and PARAM_SET's one float field.

The MAVLink parameter protocol has two encodings (mavlink.io/en/services/parameter.html,
"Parameter Encoding"), and an autopilot says which it uses in AUTOPILOT_VERSION's
capabilities:

* C cast (MAV_PROTOCOL_CAPABILITY_PARAM_ENCODE_C_CAST; ArduPilot): every value is cast to
  a float, integers included, so an integer parameter's 60 travels as 60.0.
* bytewise (MAV_PROTOCOL_CAPABILITY_PARAM_ENCODE_BYTEWISE; PX4): an integer parameter's
  bytes are copied into the float's four bytes, so 60 travels as the float whose bit
  pattern is the integer 60 (8.4e-44), and -1 as a NaN.

Read as a float, a bytewise integer is garbage (MAV_SYS_ID 1 reads 1.4e-45), and a float
written to a bytewise integer stores garbage (60.0 lands as 1114636288). Values are
decoded from, and encoded to, the four bytes themselves: a float32 NaN that went through
a Python float can lose its signalling bit, and with it an integer's value.
"""

from __future__ import annotations

import math
import struct
from typing import Any, Literal

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

ParamEncoding = Literal["c_cast", "bytewise"]

# MAV_PARAM_TYPE -> struct format of the integer types that fit in the four bytes
_INTEGER_FORMATS: dict[int, str] = {
    mavlink2.MAV_PARAM_TYPE_UINT8: "<B",
    mavlink2.MAV_PARAM_TYPE_INT8: "<b",
    mavlink2.MAV_PARAM_TYPE_UINT16: "<H",
    mavlink2.MAV_PARAM_TYPE_INT16: "<h",
    mavlink2.MAV_PARAM_TYPE_UINT32: "<I",
    mavlink2.MAV_PARAM_TYPE_INT32: "<i",
}
_BYTEWISE = mavlink2.MAV_PROTOCOL_CAPABILITY_PARAM_ENCODE_BYTEWISE
# C_CAST's bit, and the older PARAM_FLOAT that ArduPilot set before C_CAST existed
_C_CAST = mavlink2.MAV_PROTOCOL_CAPABILITY_PARAM_ENCODE_C_CAST | (
    mavlink2.MAV_PROTOCOL_CAPABILITY_PARAM_FLOAT
)
_V2_HEADER = 10
_V1_HEADER = 6


def encoding_from_capabilities(capabilities: int) -> ParamEncoding | None:
    """The encoding AUTOPILOT_VERSION.capabilities advertises; None if it names neither."""
    if capabilities & _BYTEWISE:
        return "bytewise"
    if capabilities & _C_CAST:
        return "c_cast"
    return None


def default_encoding(autopilot: str) -> ParamEncoding:
    """What an autopilot that does not say uses (QGroundControl assumes the same)."""
    return "bytewise" if autopilot == "px4" else "c_cast"


def is_integer(param_type: int) -> bool:
    return param_type in _INTEGER_FORMATS


def wire_bytes(message: Any) -> bytes:
    """The four bytes of a received PARAM_VALUE's (or PARAM_SET's) param_value, the
    message's first field, exactly as they came (MAVLink 2 drops trailing zero bytes)."""
    frame = bytes(message.get_msgbuf())
    header = _V2_HEADER if frame[:1] == b"\xfd" else _V1_HEADER
    length = frame[1]
    return frame[header : header + min(4, length)].ljust(4, b"\x00")


def decode(raw: bytes, param_type: int, encoding: ParamEncoding) -> float:
    """A parameter's value from its four wire bytes."""
    fmt = _INTEGER_FORMATS.get(param_type)
    if encoding == "bytewise" and fmt is not None:
        size = struct.calcsize(fmt)
        return float(struct.unpack(fmt, raw[:size])[0])
    return float(struct.unpack("<f", raw)[0])


def encode(value: float, param_type: int, encoding: ParamEncoding) -> bytes:
    """The four wire bytes for ``value``; ValueError naming the rule it breaks when the
    parameter's type cannot hold it (not an integer, out of range, not finite)."""
    if not math.isfinite(value):
        raise ValueError(f"{value} is not a finite number")
    fmt = _INTEGER_FORMATS.get(param_type)
    if fmt is not None:
        if value != int(value):
            raise ValueError(f"{value:g} is not an integer, and the parameter is one")
        low, high = _integer_range(fmt)
        if not low <= value <= high:
            raise ValueError(f"{value:g} is outside the parameter's type ({low}..{high})")
        if encoding == "bytewise":
            return struct.pack(fmt, int(value)).ljust(4, b"\x00")
    try:
        return struct.pack("<f", value)
    except OverflowError as error:
        raise ValueError(f"{value:g} does not fit a float32") from error


def _integer_range(fmt: str) -> tuple[int, int]:
    bits = struct.calcsize(fmt) * 8
    if fmt[-1].isupper():  # unsigned
        return 0, 2**bits - 1
    return -(2 ** (bits - 1)), 2 ** (bits - 1) - 1


class ParamSetBytes(mavlink2.MAVLink_param_set_message):  # type: ignore[misc]
    """PARAM_SET whose param_value goes out as exactly the given four bytes: packed
    through a Python float, a bytewise integer that is a signalling NaN's bit pattern
    would come out changed."""

    def __init__(
        self,
        target_system: int,
        target_component: int,
        param_id: bytes,
        raw: bytes,
        param_type: int,
    ) -> None:
        super().__init__(
            target_system, target_component, param_id, struct.unpack("<f", raw)[0], param_type
        )
        self._raw = raw

    def pack(self, mav: Any, force_mavlink1: bool = False) -> bytes:
        rest = self.unpacker.pack(
            0.0, self.target_system, self.target_component, self._param_id_raw, self.param_type
        )[4:]
        packed: bytes = self._pack(mav, self.crc_extra, self._raw + rest, force_mavlink1)
        return packed
