"""Is an uploaded file a .tlog? Checked as it streams in, so a bad one stops early.

A .tlog (QGroundControl, MAVProxy, our agent's recorder) is a run of records: an 8-byte
big-endian count of microseconds since the Unix epoch, then one MAVLink frame exactly as
it arrived (v1: magic 0xFE; v2: magic 0xFD, with a 13-byte signature when its first
incompatibility flag is set). Every record must be that shape; the frames of the first
``crc_check_bytes`` must also carry the right CRC for their message (pymavlink's
CRC_EXTRA), which a file of zeros or of anything else does not. The CRC is not checked
all the way, because pymavlink's CRC is pure Python (about a second per megabyte).
Messages this dialect does not know are let through on their shape alone.

A last record cut short (a recorder that lost power mid-write) is tolerated; a file
without one whole frame is not a .tlog.
"""

from __future__ import annotations

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

TIMESTAMP_BYTES = 8
_V1, _V2 = 0xFE, 0xFD
_V1_HEADER, _V2_HEADER = 6, 10
_CRC_BYTES = 2
_SIGNATURE_BYTES = 13
_SIGNED = 0x01  # MAVLINK_IFLAG_SIGNED, the only incompatibility flag MAVLink defines
DEFAULT_CRC_CHECK_BYTES = 256 * 1024


class InvalidTlog(ValueError):
    def __init__(self, offset: int, reason: str) -> None:
        super().__init__(f"not a MAVLink .tlog: {reason} (at byte {offset})")


class TlogChecker:
    """Feed it the upload chunk by chunk; it raises InvalidTlog at the first record that
    is not a timestamp and a MAVLink frame."""

    def __init__(self, crc_check_bytes: int = DEFAULT_CRC_CHECK_BYTES) -> None:
        self.crc_check_bytes = crc_check_bytes
        self.frames = 0
        self._buffer = bytearray()
        self._offset = 0  # of the buffer's first byte in the file

    def feed(self, chunk: bytes) -> None:
        self._buffer += chunk
        buffer, at = self._buffer, 0
        while (size := self._record_size(buffer, at)) is not None and at + size <= len(buffer):
            if self._offset + at < self.crc_check_bytes:
                self._check_crc(buffer, at + TIMESTAMP_BYTES, size - TIMESTAMP_BYTES)
            self.frames += 1
            at += size
        del buffer[:at]
        self._offset += at

    def finish(self) -> int:
        """The number of whole frames; raises if there was not one."""
        if self.frames == 0:
            raise InvalidTlog(self._offset, "no complete MAVLink frame")
        return self.frames

    def _record_size(self, buffer: bytearray, at: int) -> int | None:
        """The record's length from its header, or None until enough of it is here."""
        header_at = at + TIMESTAMP_BYTES
        if len(buffer) <= header_at + 2:
            return None
        magic, length = buffer[header_at], buffer[header_at + 1]
        if magic == _V1:
            return TIMESTAMP_BYTES + _V1_HEADER + length + _CRC_BYTES
        if magic != _V2:
            raise InvalidTlog(self._offset + header_at, f"0x{magic:02x} is not a MAVLink magic")
        flags = buffer[header_at + 2]
        if flags & ~_SIGNED:
            raise InvalidTlog(self._offset + header_at, f"unknown incompat_flags 0x{flags:02x}")
        signature = _SIGNATURE_BYTES if flags & _SIGNED else 0
        return TIMESTAMP_BYTES + _V2_HEADER + length + _CRC_BYTES + signature

    def _check_crc(self, buffer: bytearray, at: int, size: int) -> None:
        v2 = buffer[at] == _V2
        header = _V2_HEADER if v2 else _V1_HEADER
        length = buffer[at + 1]
        msgid = int.from_bytes(buffer[at + 7 : at + 10], "little") if v2 else buffer[at + 5]
        known = mavlink2.mavlink_map.get(msgid)
        if known is None:
            return
        end = at + header + length
        crc = mavlink2.x25crc(bytes(buffer[at + 1 : end]))
        crc.accumulate(bytes([known.crc_extra]))
        if crc.crc != int.from_bytes(buffer[end : end + _CRC_BYTES], "little"):
            raise InvalidTlog(self._offset + at, f"bad CRC for {known.msgname}")
