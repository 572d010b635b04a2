"""LDROBOT LD06, LD19 and STL-27L, from LDROBOT's published development manuals (the LD06
and LD19 "Development Manual", the STL-27L datasheet; ldlidar_stl_ros2 reads the same).

The sensor needs no command: powered, it spins and sends 47-byte packets, little-endian::

    54 | 2C (version 1 in bits 7..5, 12 points in bits 4..0) | speed u16 (degrees per
    second) | start angle u16 (0.01 degree) | 12 x (distance u16 mm, intensity u8) |
    end angle u16 (0.01 degree) | timestamp u16 (ms, wrapping at 30000) | CRC-8

The CRC-8 covers the 46 bytes before it: polynomial 0x4D, initial value 0, no
reflection, no final XOR (the manual prints its table; `CRC_TABLE` is computed from the
polynomial). The 12 points are evenly spaced from the start to the end angle, clockwise.
There is no start-of-turn flag: a turn starts where the angle wraps past 0.
"""

from __future__ import annotations

import struct

from vehicle_agents.sensors.lidar.common import Packet, StreamParser, TurnSplitter

HEADER = b"\x54\x2c"
POINTS = 12
PACKET_BYTES = 47
POLYNOMIAL = 0x4D
_HEAD = struct.Struct("<HH")
_POINTS = struct.Struct("<" + "HB" * POINTS)


def _crc_table(polynomial: int) -> bytes:
    table = bytearray(256)
    for value in range(256):
        crc = value
        for _ in range(8):
            crc = ((crc << 1) ^ polynomial) & 0xFF if crc & 0x80 else (crc << 1) & 0xFF
        table[value] = crc
    return bytes(table)


CRC_TABLE = _crc_table(POLYNOMIAL)


def crc8(data: bytes | bytearray) -> int:
    crc = 0
    table = CRC_TABLE
    for byte in data:
        crc = table[crc ^ byte]
    return crc


class LdlidarParser(StreamParser):
    def __init__(self) -> None:
        super().__init__()
        self.splitter = TurnSplitter()
        self.timestamp_ms: int | None = None  # the last packet's, for the probe

    def _parse(self, buffer: bytearray, out: list[Packet]) -> int:
        start = 0
        size = len(buffer)
        while True:
            at = buffer.find(HEADER, start)
            if at < 0:
                keep = 1 if size > start and buffer[-1] == 0x54 else 0
                self.skip(size - start - keep)
                return size - keep
            self.skip(at - start)
            if size - at < PACKET_BYTES:
                return at
            packet = buffer[at : at + PACKET_BYTES]
            if crc8(packet[:46]) != packet[46]:
                self.stats.drops["bad_crc"] += 1
                start = at + 1
                continue
            speed, first = _HEAD.unpack_from(packet, 2)
            fields = _POINTS.unpack_from(packet, 6)
            last, self.timestamp_ms = _HEAD.unpack_from(packet, 42)
            span = (last - first) % 36000
            step = span / (POINTS - 1) / 100.0
            origin = first / 100.0
            angles = [(origin + i * step) % 360.0 for i in range(POINTS)]
            self.splitter.split(angles, list(fields[0::2]), speed / 360.0 or None, out)
            start = at + PACKET_BYTES
