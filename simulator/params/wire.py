"""Parameter values on the wire, in the two encodings autopilots use (no I/O).

ArduPilot casts every value to PARAM_VALUE's float (MAV_PROTOCOL_CAPABILITY_PARAM_ENCODE_
C_CAST); PX4 copies an integer parameter's bytes into the float's four bytes
(PARAM_ENCODE_BYTEWISE, Parameters.cpp / mavlink_parameters.cpp), so its INT32 60 travels
as the float with 60's bit pattern. Bytes are read from and written to the frame itself:
through a Python float a signalling-NaN bit pattern (an integer such as 2139095041) would
not survive.
"""

from __future__ import annotations

import struct
from typing import Any

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from simulator.params.table import ParamType

_V2_MAGIC = 0xFD
_V2_HEADER, _V1_HEADER = 10, 6
_INTEGER_FORMATS: dict[int, str] = {
    ParamType.INT8: "<b",
    ParamType.INT16: "<h",
    ParamType.INT32: "<i",
}


def received_value(message: Any, param_type: int, bytewise: bool) -> float:
    """A PARAM_SET's value, decoded as the autopilot encodes ``param_type``."""
    fmt = _INTEGER_FORMATS.get(param_type)
    if not bytewise or fmt is None:
        return float(message.param_value)
    frame = bytes(message.get_msgbuf())
    header = _V2_HEADER if frame[0] == _V2_MAGIC else _V1_HEADER
    raw = frame[header : header + min(4, frame[1])].ljust(4, b"\x00")
    return float(struct.unpack(fmt, raw[: struct.calcsize(fmt)])[0])


def value_bytes(value: float, param_type: ParamType, bytewise: bool) -> bytes:
    """The four bytes PARAM_VALUE carries for ``value``."""
    fmt = _INTEGER_FORMATS.get(param_type)
    if bytewise and fmt is not None:
        return struct.pack(fmt, int(value)).ljust(4, b"\x00")
    return struct.pack("<f", value)


class ParamValueBytes(mavlink2.MAVLink_param_value_message):  # type: ignore[misc]
    """PARAM_VALUE with param_value as exactly the given four bytes."""

    def __init__(self, param_id: bytes, raw: bytes, param_type: int, count: int, index: int):
        super().__init__(param_id, struct.unpack("<f", raw)[0], param_type, count, index)
        self._raw = raw

    def pack(self, mav: Any, force_mavlink1: bool = False) -> bytes:
        rest = self.unpacker.pack(
            0.0, self.param_count, self.param_index, self._param_id_raw, self.param_type
        )[4:]
        packed: bytes = self._pack(mav, self.crc_extra, self._raw + rest, force_mavlink1)
        return packed
