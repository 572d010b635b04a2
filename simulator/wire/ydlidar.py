"""The bytes a YDLIDAR sends on its serial port, made from simulated beams.

YDLIDAR's published format (the X4 development manual, the T-mini Pro user manual,
YDLidar-SDK): packets of ``AA 55 | CT | LSN | FSA (u16) | LSA (u16) | CS (u16) | LSN
samples``, little-endian. A turn starts with a zero packet (``CT & 1``, one sample); a
T-mini Pro puts the scan frequency in tenths of a hertz in ``CT >> 1`` (an X4 leaves it
0). Angles are ``(FSA >> 1) / 64`` degrees, clockwise, bit 0 set as a check bit. The
intensity version's samples are 3 bytes: intensity, then a u16 whose upper 14 bits are
the distance in millimetres (the low 2 bits carry the intensity's top bits); the X2/X4/G4
samples are a u16 of distance x 4. CS is the XOR of the header word, FSA, each sample
(an intensity sample: its first byte, then its u16), ``LSN << 8 | CT`` and LSA.

An X4's angles need the manual's second-level correction, ``AngCorrect = atan(21.8 *
(155.3 - d) / (155.3 * d))`` degrees added to each sample: this simulator puts in each
sample the range the corrected angle points at (`RangeTable`), so a reader that applies
the correction sees the world where it is.

Commands go the other way as ``A5 <cmd>``: 0x60 starts the scan, 0x65 stops it, 0x90 asks
for the device information, 0x91 for the health. A real sensor idles after power-up
until it gets 0x60 (YDLidar-SDK's driver sends stop, health, then start), and answers a
command with a response descriptor: ``A5 5A | u32 (length in bits 0..29, mode in bits
30..31: 0 one answer, 1 continuous) | type``, then the answer: 0x60 gets ``A5 5A 05 00 00
40 81`` and the packets follow; 0x91 gets ``A5 5A 03 00 00 00 06`` and 3 bytes (status: 0
good, 2 error; then a u16 error code); 0x90 gets type 0x04 and 20 bytes (model, firmware
minor and major, hardware, serial number).
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

HEADER = 0x55AA
START_SCAN = 0x60
STOP_SCAN = 0x65
GET_INFO = 0x90
GET_HEALTH = 0x91
SCAN_RESPONSE = descriptor(5, 1, 0x81)
HEALTH_RESPONSE = descriptor(3, 0, 0x06)
INFO_RESPONSE = descriptor(20, 0, 0x04)
MAX_SAMPLES = 40  # what a T-mini Pro puts in one packet
MAX_DISTANCE_MM = 0x3FFF
RETURN_INTENSITY = 180
X4_MODEL = 6
TMINI_MODEL = 150  # not a number YDLIDAR publishes: the simulator's own


def encode_angle(degrees: float) -> int:
    """FSA/LSA: 1/64 degree in bits 15..1; bit 0, the check bit, set as the sensor sets it."""
    return ((round(degrees * 64.0) % (360 * 64)) << 1) | 1


def intercept_correction(distance_mm: int) -> float:
    if distance_mm == 0:
        return 0.0
    return math.degrees(math.atan(21.8 * (155.3 - distance_mm) / (155.3 * distance_mm)))


def packet(
    ct: int, angles_deg: list[float], distances_mm: list[int], sample_bytes: int = 3
) -> bytes:
    """One packet; ``ct`` is the packet type byte (bit 0: the zero packet)."""
    count = len(distances_mm)
    fsa, lsa = encode_angle(angles_deg[0]), encode_angle(angles_deg[-1])
    samples = bytearray()
    checksum = HEADER ^ fsa ^ (count << 8 | ct) ^ lsa
    for distance in distances_mm:
        if sample_bytes == 2:
            word = min(distance, MAX_DISTANCE_MM) << 2
            samples += struct.pack("<H", word)
            checksum ^= word
            continue
        intensity = RETURN_INTENSITY if distance else 0
        word = (min(distance, MAX_DISTANCE_MM) << 2) | (intensity >> 8)
        samples.append(intensity & 0xFF)
        samples += struct.pack("<H", word)
        checksum ^= (intensity & 0xFF) ^ word
    return struct.pack("<HBBHHH", HEADER, ct, count, fsa, lsa, checksum) + bytes(samples)


def encode_beams(
    beams: Beams, rate_hz: float, sample_bytes: int = 3, table: RangeTable | None = None
) -> bytes:
    """The packets for these beams: a zero packet where a turn starts, then packets of up
    to MAX_SAMPLES consecutive samples, never across a turn. With a ``table`` each sample
    holds the range its intercept-corrected angle points at."""
    # an X4 leaves CT's upper bits 0; a T-mini Pro reports its frequency there
    zero_ct = ((min(127, round(rate_hz * 10.0)) << 1) if sample_bytes == 3 else 0) | 1
    out = bytearray()
    index = beams.index.tolist()
    angles = beams.angle_deg.tolist()
    distances = millimetres(beams)
    if table is not None:
        table.update(index, distances)
        distances = [table.solve(a, intercept_correction) for a in angles]
    start = 0
    n = len(index)
    while start < n:
        if index[start] == 0:
            out += packet(
                zero_ct, angles[start : start + 1], distances[start : start + 1], sample_bytes
            )
            start += 1
            continue
        end = start + 1
        while end < n and end - start < MAX_SAMPLES and index[end] != 0:
            end += 1
        out += packet(0, angles[start:end], distances[start:end], sample_bytes)
        start = end
    return bytes(out)


def health(status: int = 0, error_code: int = 0) -> bytes:
    """The answer to GET_HEALTH: its descriptor and 3 bytes."""
    return HEALTH_RESPONSE + struct.pack("<BH", status, error_code)


def info(model: int) -> bytes:
    """The answer to GET_INFO: model, firmware 1.05, hardware 1, a serial number."""
    return INFO_RESPONSE + bytes([model, 5, 1, 1]) + bytes(range(1, 17))


class YdlidarEncoder:
    def __init__(self, sample_bytes: int, intercept: bool, beams: int) -> None:
        self.sample_bytes = sample_bytes
        self.table = RangeTable(beams) if intercept else None

    def encode(self, beams: Beams, rate_hz: float) -> bytes:
        return encode_beams(beams, rate_hz, self.sample_bytes, self.table)


class YdlidarCommands:
    """``A5 <cmd>`` pairs; anything else is ignored, as the sensor ignores it."""

    def __init__(self, model: int) -> None:
        self._pending = b""
        self._model = model

    def feed(self, data: bytes) -> list[Action]:
        requests, self._pending = split_requests(self._pending + data, lambda c: False)
        actions: list[Action] = []
        for command, _ in requests:
            if command == START_SCAN:
                actions.append(Start("scan", SCAN_RESPONSE))
            elif command == STOP_SCAN:
                actions.append(Stop())
            elif command == GET_HEALTH:
                actions.append(Reply(health()))
            elif command == GET_INFO:
                actions.append(Reply(info(self._model)))
        return actions


def wire_format(name: str) -> WireFormat:
    """``ydlidar`` (3-byte samples), ``ydlidar-x4`` (2-byte, intercept), ``ydlidar-g4``."""
    sample_bytes = 3 if name == "ydlidar" else 2
    intercept = name == "ydlidar-x4"
    model = TMINI_MODEL if sample_bytes == 3 else X4_MODEL
    return WireFormat(
        encoders={"scan": lambda beams: YdlidarEncoder(sample_bytes, intercept, beams)},
        commands=lambda: YdlidarCommands(model),
    )
