"""COMPONENT_METADATA (MAVLink 397), which pymavlink 2.4.50 does not define in any dialect.

PX4 answers MAV_CMD_REQUEST_MESSAGE for it with the MAVLink FTP address of its general
metadata file (component metadata protocol: https://mavlink.io/en/services/component_metadata.html).
The class below is what pymavlink's generator makes of the message's definition
(time_boot_ms uint32, file_crc uint32, uri char[100]; CRC extra 182, computed as mavparse
does), so the agent decodes it and the simulator sends it. `register` adds it to a
dialect's decoder table.
"""

from __future__ import annotations

import struct
from typing import Any

from pymavlink.dialects.v20 import ardupilotmega

MAVLINK_MSG_ID_COMPONENT_METADATA = 397
URI_LEN = 100


class MAVLink_component_metadata_message(ardupilotmega.MAVLink_message):  # type: ignore[misc]
    id = MAVLINK_MSG_ID_COMPONENT_METADATA
    msgname = "COMPONENT_METADATA"
    fieldnames = ["time_boot_ms", "file_crc", "uri"]
    ordered_fieldnames = ["time_boot_ms", "file_crc", "uri"]
    fieldtypes = ["uint32_t", "uint32_t", "char"]
    fielddisplays_by_name: dict[str, str] = {}
    fieldenums_by_name: dict[str, str] = {}
    fieldunits_by_name: dict[str, str] = {"time_boot_ms": "ms"}
    native_format = bytearray(b"<IIc")
    orders = [0, 1, 2]
    lengths = [1, 1, 1]
    array_lengths = [0, 0, URI_LEN]
    crc_extra = 182
    unpacker = struct.Struct("<II100s")
    instance_field = None
    instance_offset = -1

    def __init__(self, time_boot_ms: int, file_crc: int, uri: bytes) -> None:
        ardupilotmega.MAVLink_message.__init__(self, self.id, self.msgname)
        self._fieldnames = self.fieldnames
        self._instance_field = self.instance_field
        self._instance_offset = self.instance_offset
        self.time_boot_ms = time_boot_ms
        self.file_crc = file_crc
        self._uri_raw = uri
        self.uri = uri.split(b"\x00", 1)[0].decode("ascii", errors="replace")

    def pack(self, mav: Any, force_mavlink1: bool = False) -> bytes:
        payload = self.unpacker.pack(self.time_boot_ms, self.file_crc, self._uri_raw)
        packed: bytes = self._pack(mav, self.crc_extra, payload, force_mavlink1=force_mavlink1)
        return packed


def register() -> None:
    """Let the ArduPilot dialect decode COMPONENT_METADATA (idempotent)."""
    ardupilotmega.mavlink_map.setdefault(
        MAVLINK_MSG_ID_COMPONENT_METADATA, MAVLink_component_metadata_message
    )
