"""The bytes a Slamtec RPLIDAR sends on its serial port, made from simulated beams.

Slamtec's published interface protocol (and its SDK's answer formats): requests are ``A5
<cmd>``, those from 0x80 up followed by ``<size> <payload> <checksum>`` (the XOR of every
byte before it). Answers start with the A5 5A descriptor (simulator/wire/formats.py):

- GET_INFO (0x50): type 0x04, 20 bytes: model, firmware minor, major, hardware, serial.
- GET_HEALTH (0x52): type 0x06, 3 bytes: status (0 good), u16 error code.
- SCAN (0x20) / FORCE_SCAN (0x21): type 0x81, then 5-byte nodes: ``S | !S << 1 | quality
  << 2`` (S = 1 on a turn's first node), u16 ``angle_q6 << 1 | 1`` (1/64 degree, check
  bit set), u16 distance in 1/4 mm.
- EXPRESS_SCAN (0x82, 5-byte payload: working mode, flags, parameter): a capsule stream,
  each capsule ``0xA << 4 | cs & 0xF``, ``0x5 << 4 | cs >> 4`` (cs: XOR of the bytes after
  these two), u16 start angle in 1/64 degree with bit 15 set on the first capsule, then:
  * legacy (type 0x82, 84 bytes): 16 cabins of u16 d1, u16 d2 (distance << 2, the angle
    compensation's bits 5..4 in bits 1..0), u8 (the two compensations' bits 3..0);
  * dense (type 0x85, 84 bytes): 40 u16 distances in mm;
  * ultra (type 0x84, 132 bytes): 32 u32 cabins of a 12-bit major distance on a variable
    bit scale and two signed 10-bit predictions (see the agent's parser for the rules).
  A capsule's samples lie evenly between its start angle and the next capsule's (less each
  sample's compensation), so the simulator sends a capsule once it has the next's first
  sample. The simulated head's samples are evenly spaced, so the legacy compensation is 0;
  an ultra capsule's decoder subtracts a range-dependent triangulation offset, so each
  sample holds the range that offset angle points at (`RangeTable`).
- STOP (0x25) and RESET (0x40) stop the scan; SET_MOTOR_PWM (0xF0) and MOTOR_SPEED_CTRL
  (0xA8) are taken without an answer, as the sensor takes them.

Which capsule the express scan answers with is the simulated model's (``--lidar-format``):
``rplidar-express`` legacy, ``rplidar-dense`` dense, ``rplidar-ultra`` ultra; plain
``rplidar`` answers express with legacy capsules too.
"""

from __future__ import annotations

import math
import struct

from simulator.sensors.lidar import Beams
from simulator.wire.formats import (
    Action,
    RangeTable,
    Reply,
    Start,
    Stop,
    WireFormat,
    descriptor,
    millimetres,
    split_requests,
)

STOP = 0x25
RESET = 0x40
SCAN = 0x20
FORCE_SCAN = 0x21
EXPRESS_SCAN = 0x82
GET_INFO = 0x50
GET_HEALTH = 0x52
STANDARD = 0x81
LEGACY = 0x82
ULTRA = 0x84
DENSE = 0x85
CAPSULE_BYTES = {LEGACY: 84, DENSE: 84, ULTRA: 132}
SAMPLES = {LEGACY: 32, DENSE: 40, ULTRA: 96}
QUALITY = 47
MAX_Q2 = 0xFFFF
MODELS = {"rplidar": 0x18, "rplidar-express": 0x18, "rplidar-dense": 0x61, "rplidar-ultra": 0x31}
_NODE = struct.Struct("<BHH")
_OFFSET_NEAR_Q16 = int(7.5 * math.pi * 65536 / 180.0)
_OFFSET_FAR_Q16 = int(8 * math.pi * 65536 / 180.0)


def ultra_offset_deg(distance_mm: int) -> float:
    """The triangulation offset Slamtec's SDK subtracts from an ultra sample's angle."""
    q2 = distance_mm * 4
    offset = _OFFSET_NEAR_Q16
    if q2 >= 200:
        k2 = 98361 // q2
        offset = _OFFSET_FAR_Q16 - k2 * 64 - k2**3 // 98304
    return math.degrees(offset / 65536.0)


def scale_encode(distance_mm: int) -> tuple[int, int]:
    """A distance as an ultra cabin's 12-bit major (nearest), and its scale level."""
    for floor, base, level in ((16384, 3328, 4), (4096, 1792, 3), (2048, 1280, 2), (512, 512, 1)):
        if distance_mm >= floor:
            return min(4095, base + ((distance_mm - floor + (1 << level >> 1)) >> level)), level
    return distance_mm, 0


def scale_decode(scaled: int) -> tuple[int, int]:
    for base, floor, level in ((3328, 16384, 4), (1792, 4096, 3), (1280, 2048, 2), (512, 512, 1)):
        if scaled >= base:
            return floor + ((scaled - base) << level), level
    return scaled, 0


def node(start: bool, angle_deg: float, distance_mm: int) -> bytes:
    quality = QUALITY if distance_mm else 0
    flags = (1 if start else 2) | quality << 2
    angle_q6 = round(angle_deg * 64.0) % (360 * 64)
    return _NODE.pack(flags, angle_q6 << 1 | 1, min(MAX_Q2, distance_mm * 4))


def capsule(kind: int, start_deg: float, first: bool, body: bytes) -> bytes:
    """A capsule around its cabins: sync nibbles, checksum, start angle and flag."""
    word = round(start_deg * 64.0) % (360 * 64) | (0x8000 if first else 0)
    rest = struct.pack("<H", word) + body
    check = 0
    for byte in rest:
        check ^= byte
    assert len(rest) + 2 == CAPSULE_BYTES[kind]
    return bytes([0xA0 | check & 0xF, 0x50 | check >> 4]) + rest


def legacy_cabins(distances: list[int], offsets_q3: list[int] | None = None) -> bytes:
    """16 cabins from 32 distances (mm) and their 6-bit angle compensations (1/8 degree)."""
    offsets = offsets_q3 or [0] * 32
    out = bytearray()
    for k in range(16):
        o1, o2 = offsets[2 * k], offsets[2 * k + 1]
        d1 = min(0x3FFF, distances[2 * k]) << 2 | (o1 >> 4) & 3
        d2 = min(0x3FFF, distances[2 * k + 1]) << 2 | (o2 >> 4) & 3
        out += struct.pack("<HHB", d1, d2, (o1 & 0xF) | (o2 & 0xF) << 4)
    return bytes(out)


def dense_cabins(distances: list[int]) -> bytes:
    return struct.pack("<40H", *(min(0xFFFF, d) for d in distances))


def _predict(value: int, base: int, level: int) -> int:
    """A 10-bit prediction of ``value`` from ``base`` (0x1FF: no return, or out of reach)."""
    if value == 0:
        return 0x1FF
    step = (value - base) / (1 << level)
    predict = math.floor(step + 0.5)
    return predict & 0x3FF if -511 <= predict <= 510 else 0x1FF


def ultra_cabins(distances: list[int], next_first: int) -> bytes:
    """32 cabins from 96 distances (mm); ``next_first``: the next capsule's first."""
    majors = [scale_encode(d)[0] for d in distances[0::3]] + [scale_encode(next_first)[0]]
    out = bytearray()
    for k in range(32):
        major, level = scale_decode(majors[k])
        major2, level2 = scale_decode(majors[k + 1])
        base, base_level = (major2, level2) if major == 0 and major2 else (major, level)
        p1 = _predict(distances[3 * k + 1], base, base_level)
        p2 = _predict(distances[3 * k + 2], major2, level2)
        out += struct.pack("<I", majors[k] | p1 << 12 | p2 << 22)
    return bytes(out)


class StandardEncoder:
    def __init__(self, beams: int) -> None:
        del beams

    def encode(self, beams: Beams, rate_hz: float) -> bytes:
        index = beams.index.tolist()
        angles = beams.angle_deg.tolist()
        return b"".join(
            node(i == 0, a, d) for i, a, d in zip(index, angles, millimetres(beams), strict=True)
        )


class CapsuleEncoder:
    """Capsules of one kind; samples wait until a capsule and the next's first are here."""

    def __init__(self, kind: int, beams: int) -> None:
        self.kind = kind
        self._angles: list[float] = []
        self._distances: list[int] = []
        self._first = True
        self._table = RangeTable(beams) if kind == ULTRA else None

    def encode(self, beams: Beams, rate_hz: float) -> bytes:
        angles = beams.angle_deg.tolist()
        distances = millimetres(beams)
        if self._table is not None:
            self._table.update(beams.index.tolist(), distances)
            table = self._table
            distances = [table.solve(a, lambda d: -ultra_offset_deg(d)) for a in angles]
        self._angles += angles
        self._distances += distances
        count = SAMPLES[self.kind]
        out = bytearray()
        while len(self._angles) > count:
            start = self._angles[0]
            batch, following = self._distances[:count], self._distances[count]
            if self.kind == LEGACY:
                body = legacy_cabins(batch)
            elif self.kind == DENSE:
                body = dense_cabins(batch)
            else:
                body = ultra_cabins(batch, following)
            out += capsule(self.kind, start, self._first, body)
            self._first = False
            del self._angles[:count]
            del self._distances[:count]
        return bytes(out)


def health(status: int = 0, error_code: int = 0) -> bytes:
    return descriptor(3, 0, 0x06) + struct.pack("<BH", status, error_code)


def info(model: int) -> bytes:
    return descriptor(20, 0, 0x04) + bytes([model, 29, 1, 7]) + bytes(range(16, 32))


class RplidarCommands:
    def __init__(self, express: int, model: int) -> None:
        self._pending = b""
        self._express = express
        self._model = model

    def feed(self, data: bytes) -> list[Action]:
        # commands from 0x80 up carry a payload (the protocol's rule)
        requests, self._pending = split_requests(self._pending + data, lambda c: c >= 0x80)
        actions = [self._action(command, payload) for command, payload in requests]
        return [action for action in actions if action is not None]

    def _action(self, command: int, payload: bytes) -> Action | None:
        if command in (STOP, RESET):
            return Stop()
        if command in (SCAN, FORCE_SCAN):
            return Start("standard", descriptor(5, 1, STANDARD))
        if command == EXPRESS_SCAN and len(payload) == 5:
            kind = self._express
            return Start(f"capsule-{kind:02x}", descriptor(CAPSULE_BYTES[kind], 1, kind))
        if command == GET_HEALTH:
            return Reply(health())
        if command == GET_INFO:
            return Reply(info(self._model))
        return None


def wire_format(name: str) -> WireFormat:
    express = {"rplidar-dense": DENSE, "rplidar-ultra": ULTRA}.get(name, LEGACY)
    return WireFormat(
        encoders={
            "standard": StandardEncoder,
            f"capsule-{express:02x}": lambda beams: CapsuleEncoder(express, beams),
        },
        commands=lambda: RplidarCommands(express, MODELS[name]),
    )
