"""The bytes an LDROBOT LD06 / LD19 / STL-27L sends, made from simulated beams.

LDROBOT's published development manuals: the sensor takes no command and sends, from
power-up, 47-byte packets, little-endian: ``54 2C | speed u16 (degrees/s) | start angle
u16 (0.01 degree) | 12 x (distance u16 mm, intensity u8) | end angle u16 | timestamp u16
(ms, wrapping at 30000) | CRC-8`` (polynomial 0x4D, initial 0, over the 46 bytes before
it). Points are evenly spaced from start to end angle, clockwise; a packet may straddle
the 0-degree mark, as a real one does.
"""

from __future__ import annotations

import struct

from simulator.sensors.lidar import Beams
from simulator.wire.formats import Action, WireFormat, millimetres

POINTS = 12
POLYNOMIAL = 0x4D
INTENSITY = 200
TIMESTAMP_WRAP_MS = 30000


def _table() -> bytes:
    table = bytearray(256)
    for value in range(256):
        crc = value
        for _ in range(8):
            crc = ((crc << 1) ^ POLYNOMIAL if crc & 0x80 else crc << 1) & 0xFF
        table[value] = crc
    return bytes(table)


_CRC = _table()


def crc8(data: bytes) -> int:
    crc = 0
    for byte in data:
        crc = _CRC[crc ^ byte]
    return crc


def packet(
    speed_dps: int, angles_deg: list[float], distances_mm: list[int], stamp_ms: int
) -> bytes:
    """One packet of 12 points."""
    body = struct.pack("<BBHH", 0x54, 0x2C, speed_dps, round(angles_deg[0] * 100) % 36000)
    for distance in distances_mm:
        body += struct.pack("<HB", min(0xFFFF, distance), INTENSITY if distance else 0)
    body += struct.pack("<HH", round(angles_deg[-1] * 100) % 36000, stamp_ms % TIMESTAMP_WRAP_MS)
    return body + bytes([crc8(body)])


class LdlidarEncoder:
    def __init__(self, beams: int) -> None:
        del beams
        self._angles: list[float] = []
        self._distances: list[int] = []
        self._times: list[float] = []

    def encode(self, beams: Beams, rate_hz: float) -> bytes:
        self._angles += beams.angle_deg.tolist()
        self._distances += millimetres(beams)
        self._times += beams.time_s.tolist()
        out = bytearray()
        speed = round(rate_hz * 360.0)
        while len(self._angles) >= POINTS:
            stamp = round(self._times[POINTS - 1] * 1000.0)
            out += packet(speed, self._angles[:POINTS], self._distances[:POINTS], stamp)
            del self._angles[:POINTS], self._distances[:POINTS], self._times[:POINTS]
        return bytes(out)


class NoCommands:
    def feed(self, data: bytes) -> list[Action]:
        return []


def wire_format(name: str) -> WireFormat:
    del name
    return WireFormat(encoders={"scan": LdlidarEncoder}, commands=NoCommands, streams="scan")
