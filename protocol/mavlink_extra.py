"""MAVLink messages the agent needs that pymavlink 2.4.50's ArduPilot dialect lacks.

- COMPONENT_METADATA (397), in no pymavlink dialect: PX4 answers MAV_CMD_REQUEST_MESSAGE
  for it with the MAVLink FTP address of its general metadata file (component metadata
  protocol: https://mavlink.io/en/services/component_metadata.html).
- The standard-modes messages AVAILABLE_MODES (435), CURRENT_MODE (436) and
  AVAILABLE_MODES_MONITOR (437), which PX4 (1.15 on) and ArduPilot (4.7 on) send. pymavlink
  has them only in its development dialect, and importing that dialect beside the
  ArduPilot one costs a small board several MB of memory for three messages.

Each class is what pymavlink's generator makes of the message's XML definition: the
fields in definition order, the wire order (sorted by type size), the struct format and the
CRC extra (as mavparse computes it; `tests/unit/protocol/test_mavlink_extra.py` checks them against
pymavlink's own classes where it has them). `register` adds them to a dialect's decoder table.
"""

from __future__ import annotations

import struct
from typing import Any, ClassVar

from pymavlink.dialects.v20 import ardupilotmega

MAVLINK_MSG_ID_COMPONENT_METADATA = 397
MAVLINK_MSG_ID_AVAILABLE_MODES = 435
MAVLINK_MSG_ID_CURRENT_MODE = 436
MAVLINK_MSG_ID_AVAILABLE_MODES_MONITOR = 437
URI_LEN = 100
MODE_NAME_LEN = 35


class _ExtraMessage(ardupilotmega.MAVLink_message):  # type: ignore[misc]
    """A generated-style message: positional fields in definition order (as pymavlink's
    decoder passes them), char arrays kept raw for packing and as text for reading."""

    id: ClassVar[int]
    msgname: ClassVar[str]
    fieldnames: ClassVar[list[str]]
    ordered_fieldnames: ClassVar[list[str]]
    char_fields: ClassVar[frozenset[str]] = frozenset()
    crc_extra: ClassVar[int]
    unpacker: ClassVar[struct.Struct]
    fielddisplays_by_name: ClassVar[dict[str, str]] = {}
    fieldenums_by_name: ClassVar[dict[str, str]] = {}
    fieldunits_by_name: ClassVar[dict[str, str]] = {}
    instance_field = None
    instance_offset = -1

    def __init__(self, *values: Any) -> None:
        ardupilotmega.MAVLink_message.__init__(self, self.id, self.msgname)
        self._fieldnames = self.fieldnames
        self._instance_field = self.instance_field
        self._instance_offset = self.instance_offset
        for name, value in zip(self.fieldnames, values, strict=True):
            if name in self.char_fields:
                raw = value if isinstance(value, bytes) else str(value).encode("ascii")
                setattr(self, f"_{name}_raw", raw)
                value = raw.split(b"\x00", 1)[0].decode("ascii", errors="replace")
            setattr(self, name, value)

    def pack(self, mav: Any, force_mavlink1: bool = False) -> bytes:
        values = [
            getattr(self, f"_{name}_raw") if name in self.char_fields else getattr(self, name)
            for name in self.ordered_fieldnames
        ]
        payload = self.unpacker.pack(*values)
        packed: bytes = self._pack(mav, self.crc_extra, payload, force_mavlink1=force_mavlink1)
        return packed


class MAVLink_component_metadata_message(_ExtraMessage):
    """time_boot_ms uint32, file_crc uint32, uri char[100]."""

    id = MAVLINK_MSG_ID_COMPONENT_METADATA
    msgname = "COMPONENT_METADATA"
    fieldnames = ["time_boot_ms", "file_crc", "uri"]
    ordered_fieldnames = ["time_boot_ms", "file_crc", "uri"]
    fieldtypes = ["uint32_t", "uint32_t", "char"]
    char_fields = frozenset({"uri"})
    fieldunits_by_name = {"time_boot_ms": "ms"}
    native_format = bytearray(b"<IIc")
    orders = [0, 1, 2]
    lengths = [1, 1, 1]
    array_lengths = [0, 0, URI_LEN]
    crc_extra = 182
    unpacker = struct.Struct("<II100s")


class MAVLink_available_modes_message(_ExtraMessage):
    """number_modes uint8, mode_index uint8, standard_mode uint8, custom_mode uint32,
    properties uint32, mode_name char[35]."""

    id = MAVLINK_MSG_ID_AVAILABLE_MODES
    msgname = "AVAILABLE_MODES"
    fieldnames = [
        "number_modes",
        "mode_index",
        "standard_mode",
        "custom_mode",
        "properties",
        "mode_name",
    ]
    ordered_fieldnames = [
        "custom_mode",
        "properties",
        "number_modes",
        "mode_index",
        "standard_mode",
        "mode_name",
    ]
    fieldtypes = ["uint8_t", "uint8_t", "uint8_t", "uint32_t", "uint32_t", "char"]
    char_fields = frozenset({"mode_name"})
    fielddisplays_by_name = {"properties": "bitmask"}
    fieldenums_by_name = {"standard_mode": "MAV_STANDARD_MODE", "properties": "MAV_MODE_PROPERTY"}
    native_format = bytearray(b"<IIBBBc")
    orders = [2, 3, 4, 0, 1, 5]
    lengths = [1, 1, 1, 1, 1, 1]
    array_lengths = [0, 0, 0, 0, 0, MODE_NAME_LEN]
    crc_extra = 134
    unpacker = struct.Struct("<IIBBB35s")


class MAVLink_current_mode_message(_ExtraMessage):
    """standard_mode uint8, custom_mode uint32, intended_custom_mode uint32."""

    id = MAVLINK_MSG_ID_CURRENT_MODE
    msgname = "CURRENT_MODE"
    fieldnames = ["standard_mode", "custom_mode", "intended_custom_mode"]
    ordered_fieldnames = ["custom_mode", "intended_custom_mode", "standard_mode"]
    fieldtypes = ["uint8_t", "uint32_t", "uint32_t"]
    fieldenums_by_name = {"standard_mode": "MAV_STANDARD_MODE"}
    native_format = bytearray(b"<IIB")
    orders = [2, 0, 1]
    lengths = [1, 1, 1]
    array_lengths = [0, 0, 0]
    crc_extra = 193
    unpacker = struct.Struct("<IIB")


class MAVLink_available_modes_monitor_message(_ExtraMessage):
    """seq uint8: changes when the list of available modes changes."""

    id = MAVLINK_MSG_ID_AVAILABLE_MODES_MONITOR
    msgname = "AVAILABLE_MODES_MONITOR"
    fieldnames = ["seq"]
    ordered_fieldnames = ["seq"]
    fieldtypes = ["uint8_t"]
    native_format = bytearray(b"<B")
    orders = [0]
    lengths = [1]
    array_lengths = [0]
    crc_extra = 30
    unpacker = struct.Struct("<B")


EXTRA_MESSAGES: tuple[type[_ExtraMessage], ...] = (
    MAVLink_component_metadata_message,
    MAVLink_available_modes_message,
    MAVLink_current_mode_message,
    MAVLink_available_modes_monitor_message,
)


def register() -> None:
    """Let the ArduPilot dialect decode these messages (idempotent)."""
    for message in EXTRA_MESSAGES:
        ardupilotmega.mavlink_map.setdefault(message.id, message)
