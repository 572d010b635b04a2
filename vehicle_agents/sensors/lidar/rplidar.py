"""Slamtec RPLIDAR (A1, A2, A3, C1, S1, S2), from Slamtec's published interface protocol
("RPLIDAR Interface Protocol and Application Notes") and its SDK's answer formats.

Requests are ``A5 <cmd>``; commands from 0x80 up carry ``<size> <payload> <checksum>``,
the checksum being the XOR of every byte before it. Answers begin with the A5 5A
descriptor (common.py). What this parser reads:

- GET_INFO (0x50), answer 0x04, 20 bytes: model, firmware minor, major, hardware, serial.
- GET_HEALTH (0x52), answer 0x06, 3 bytes: status (0 good, 1 warning, 2 error), u16 code.
- SCAN (0x20) / FORCE_SCAN (0x21), answer 0x81, 5-byte nodes: ``S | !S << 1 | quality
  << 2``, then a u16 whose bit 0 is the check bit (always 1) and bits 15..1 the angle in
  1/64 degree, then the distance in 1/4 mm. S = 1 on the first node of a new turn.
- EXPRESS_SCAN (0x82, payload: working mode u8, flags u16, param u16): the answer's type
  says which capsule follows. Every capsule starts ``sync1 << 4 | cs & 0xF``, ``sync2 << 4
  | cs >> 4`` (sync1 0xA, sync2 0x5, cs the XOR of all the bytes after these two), then a
  u16 whose bits 14..0 are the start angle in 1/64 degree and bit 15 the "new measurement"
  flag. Its samples lie between its start angle and the next capsule's, so a capsule is
  decoded when the next one arrives.
  * 0x82, legacy express, 84 bytes: 16 cabins of ``u16 d1, u16 d2, u8 offsets``. Distances
    are ``d >> 2`` mm; each sample's angle compensation is 6 bits in 1/8 degree, its low 4
    bits in the offsets' nibble and its high 2 in ``d & 3``, subtracted from the evenly
    spaced angle. (The protocol text calls it signed; Slamtec's SDK, which every shipped
    sensor is used with, reads it unsigned, and so does this parser.)
  * 0x85, dense, 84 bytes: 40 u16 distances in mm, evenly spaced, no compensation.
  * 0x84, ultra, 132 bytes: 32 u32 cabins ``major (12 bits) | predict1 (10, signed) << 12
    | predict2 (10, signed) << 22``, three samples each. The major is a variable-bit-scale
    distance (below 512: itself; from 512, 1280, 1792, 3328 up it counts 2, 4, 8, 16 mm
    from 512, 2048, 4096, 16384); sample 2 is this cabin's base plus predict1 scaled as
    its major, sample 3 the next cabin's major plus predict2 scaled as that one (the
    extreme predict values, 0x1FF and -0x200, mean no return). Angles are evenly spaced
    less the triangulation offset for each distance, as the SDK computes it.

Motor: an A1, or an A2/A3 on Slamtec's USB adapter, spins when the adapter's DTR line is
low; an A2/A3 also takes SET_MOTOR_PWM (0xF0, u16 duty 0..1023), and the S and C series
spin by themselves (newer firmware takes MOTOR_SPEED_CTRL, 0xA8, u16 rpm).
"""

from __future__ import annotations

import math
import struct

from vehicle_agents.sensors.lidar.common import (
    HEALTH_ANSWER,
    INFO_ANSWER,
    MODE_CONTINUOUS,
    MODE_SINGLE,
    Packet,
    StreamParser,
    TurnSplitter,
    wrap360,
)

SYNC = 0xA5
STOP = 0x25
RESET = 0x40
SCAN = 0x20
FORCE_SCAN = 0x21
EXPRESS_SCAN = 0x82
GET_INFO = 0x50
GET_HEALTH = 0x52
SET_MOTOR_PWM = 0xF0
MOTOR_SPEED_CTRL = 0xA8
DEFAULT_PWM = 660  # the SDK's default duty for an A2/A3

STANDARD = 0x81
LEGACY_CAPSULE = 0x82
ULTRA_CAPSULE = 0x84
DENSE_CAPSULE = 0x85
# answer type -> (mode, length)
ANSWERS = {
    INFO_ANSWER: (MODE_SINGLE, 20),
    HEALTH_ANSWER: (MODE_SINGLE, 3),
    STANDARD: (MODE_CONTINUOUS, 5),
    LEGACY_CAPSULE: (MODE_CONTINUOUS, 84),
    ULTRA_CAPSULE: (MODE_CONTINUOUS, 132),
    DENSE_CAPSULE: (MODE_CONTINUOUS, 84),
}
SCAN_ANSWERS = (STANDARD, LEGACY_CAPSULE, ULTRA_CAPSULE, DENSE_CAPSULE)
NODE_BYTES = 5
MAX_ANGLE_WORD = (360 * 64) << 1  # a node's angle word from 360 degrees up
SERIES = {1: "A1", 2: "A2", 3: "A3"}  # the model byte's high nibble, where we are sure of it
_NODE = struct.Struct("<BHH")
_U16 = struct.Struct("<H")
_ULTRA = struct.Struct("<32I")
_DENSE = struct.Struct("<40H")
_DEG_PER_RAD_Q16 = 180.0 / math.pi / 65536.0
# the SDK's integer constants for the triangulation offset, in radians << 16
_OFFSET_NEAR_Q16 = int(7.5 * math.pi * 65536 / 180.0)
_OFFSET_FAR_Q16 = int(8 * math.pi * 65536 / 180.0)


def request(command: int, payload: bytes = b"") -> bytes:
    """A request: ``A5 cmd``, and for a payload its size, the payload and the XOR checksum."""
    if not payload:
        return bytes([SYNC, command])
    head = bytes([SYNC, command, len(payload)]) + payload
    checksum = 0
    for byte in head:
        checksum ^= byte
    return head + bytes([checksum])


def express_scan(working_mode: int = 0) -> bytes:
    return request(EXPRESS_SCAN, struct.pack("<BHH", working_mode, 0, 0))


def motor_pwm(duty: int) -> bytes:
    return request(SET_MOTOR_PWM, struct.pack("<H", duty))


def varbitscale(scaled: int) -> tuple[int, int]:
    """An ultra cabin's 12-bit major as (distance in mm, scale level)."""
    if scaled >= 3328:
        return 16384 + ((scaled - 3328) << 4), 4
    if scaled >= 1792:
        return 4096 + ((scaled - 1792) << 3), 3
    if scaled >= 1280:
        return 2048 + ((scaled - 1280) << 2), 2
    if scaled >= 512:
        return 512 + ((scaled - 512) << 1), 1
    return scaled, 0


def ultra_offset_deg(distance_mm: int) -> float:
    """The triangulation offset an ultra sample's angle loses, as Slamtec's SDK computes it
    (in integer radians << 16 from the distance in 1/4 mm)."""
    q2 = distance_mm << 2
    offset = _OFFSET_NEAR_Q16
    if q2 >= 200:
        k2 = 98361 // q2
        offset = _OFFSET_FAR_Q16 - (k2 << 6) - (k2 * k2 * k2) // 98304
    return offset * _DEG_PER_RAD_Q16


def _series_name(info: bytes) -> str | None:
    series = SERIES.get(info[0] >> 4)
    return None if series is None else f"RPLIDAR {series}"


def _signed10(value: int) -> int:
    return value - 1024 if value & 0x200 else value


class RplidarParser(StreamParser):
    """``scan``: the answer type to expect before any descriptor is seen (a sensor already
    scanning when the agent starts); a descriptor switches to whatever it announces."""

    def __init__(self, scan: int | None = STANDARD) -> None:
        super().__init__()
        self.scan = scan
        self.splitter = TurnSplitter()
        self._previous: bytes | None = None  # the last capsule, waiting for the next one's angle

    def _set_scan(self, kind: int) -> None:
        self.scan = kind
        self._previous = None
        self.splitter.reset()

    def _parse(self, buffer: bytearray, out: list[Packet]) -> int:
        at = 0
        size = len(buffer)
        angles: list[float] = []  # the standard scan's nodes, grouped into packets
        distances: list[int] = []
        zero = False
        while True:
            if size - at < 2:
                break
            if buffer[at] == SYNC and buffer[at + 1] == 0x5A:
                found = self.answer(buffer, at, ANSWERS, _series_name)
                if found is None:
                    break
                taken, answered = found
                if taken:
                    if answered in SCAN_ANSWERS:
                        self._set_scan(answered)
                    if angles:
                        out.append(Packet(zero, None, angles, distances))
                        angles, distances, zero = [], [], False
                    at += taken
                    continue
            kind = self.scan
            if kind == STANDARD:
                if size - at < NODE_BYTES:
                    break
                flags, angle, distance = _NODE.unpack_from(buffer, at)
                if (flags & 1) == ((flags >> 1) & 1) or not angle & 1:
                    self.skip(1, "bad_check_bits")
                    at += 1
                    continue
                if angle >= MAX_ANGLE_WORD:  # 360 degrees or more: not a node, misaligned
                    self.skip(1, "bad_angle")
                    at += 1
                    continue
                if flags & 1 and angles:
                    out.append(Packet(zero, None, angles, distances))
                    angles, distances = [], []
                if flags & 1:
                    zero = True
                angles.append((angle >> 1) / 64.0)
                distances.append((distance + 2) >> 2)
                at += NODE_BYTES
                continue
            if kind in (LEGACY_CAPSULE, DENSE_CAPSULE, ULTRA_CAPSULE):
                length = ANSWERS[kind][1]
                if buffer[at] >> 4 != 0xA or buffer[at + 1] >> 4 != 0x5:
                    self.skip(1)
                    self._previous = None  # a capsule may be lost: its angle with it
                    at += 1
                    continue
                if size - at < length:
                    break
                capsule = bytes(buffer[at : at + length])
                check = 0
                for byte in capsule[2:]:
                    check ^= byte
                if check != (capsule[0] & 0xF) | (capsule[1] & 0xF) << 4:
                    self.stats.drops["bad_checksum"] += 1
                    self._previous = None  # its samples cannot be placed without this angle
                    at += 1
                    continue
                self._capsule(kind, capsule, out)
                at += length
                continue
            self.skip(1)  # no scan started yet: nothing but answers is expected
            at += 1
        if angles:
            out.append(Packet(zero, None, angles, distances))
        return at

    def _capsule(self, kind: int, capsule: bytes, out: list[Packet]) -> None:
        (word,) = _U16.unpack_from(capsule, 2)
        if word & 0x8000:  # the first capsule after a (re)start: no previous to decode
            self._previous = capsule
            self.splitter.reset()
            return
        previous, self._previous = self._previous, capsule
        if previous is None:
            return
        start = (_U16.unpack_from(previous, 2)[0] & 0x7FFF) / 64.0
        span = (word & 0x7FFF) / 64.0 - start
        if span < 0.0:
            span += 360.0
        if kind == LEGACY_CAPSULE:
            angles, distances = _legacy(previous, start, span)
        elif kind == DENSE_CAPSULE:
            distances = list(_DENSE.unpack_from(previous, 4))
            step = span / 40.0
            angles = [(start + i * step) % 360.0 for i in range(40)]
        else:
            angles, distances = _ultra(previous, capsule, start, span)
        self.splitter.split(angles, distances, None, out)


def _legacy(capsule: bytes, start: float, span: float) -> tuple[list[float], list[int]]:
    step = span / 32.0
    angles: list[float] = []
    distances: list[int] = []
    for k in range(16):
        d1, d2, offsets = struct.unpack_from("<HHB", capsule, 4 + 5 * k)
        base = start + 2 * k * step
        angles.append(wrap360(base - ((offsets & 0xF) | (d1 & 3) << 4) / 8.0))
        angles.append(wrap360(base + step - ((offsets >> 4) | (d2 & 3) << 4) / 8.0))
        distances.append(d1 >> 2)
        distances.append(d2 >> 2)
    return angles, distances


def _ultra(
    capsule: bytes, following: bytes, start: float, span: float
) -> tuple[list[float], list[int]]:
    cabins = _ULTRA.unpack_from(capsule, 4)
    next_major = _ULTRA.unpack_from(following, 4)[0] & 0xFFF
    step = span / 96.0
    angles: list[float] = []
    distances: list[int] = []
    for k, cabin in enumerate(cabins):
        major, level = varbitscale(cabin & 0xFFF)
        major2, level2 = varbitscale((cabins[k + 1] if k < 31 else next_major) & 0xFFF)
        base, base_level = (major2, level2) if major == 0 and major2 else (major, level)
        predict1 = _signed10((cabin >> 12) & 0x3FF)
        predict2 = _signed10(cabin >> 22)
        second = 0 if predict1 in (511, -512) else (predict1 << base_level) + base
        third = 0 if predict2 in (511, -512) else (predict2 << level2) + major2
        for i, distance in enumerate((major, max(0, second), max(0, third))):
            angle = start + (3 * k + i) * step - ultra_offset_deg(distance)
            angles.append(wrap360(angle))
            distances.append(distance)
    return angles, distances
