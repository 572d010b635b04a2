"""The bytes a YDLIDAR T-mini Pro sends on its serial port, made from simulated beams.

YDLIDAR's published format (YDLidar-SDK, "Communication Protocol"): packets of
``AA 55 | CT | LSN | FSA (u16) | LSA (u16) | CS (u16) | LSN samples``, little-endian. A
turn starts with a zero packet (``CT & 1``, one sample) whose ``CT >> 1`` is the scan
frequency in tenths of a hertz. Angles are ``(FSA >> 1) / 64`` degrees, clockwise; the
intensity version's samples are 3 bytes: intensity, then a u16 whose upper 14 bits are the
distance in millimetres (the low 2 bits carry the intensity's top bits). CS is the XOR of
the header word, FSA, each sample (its first byte, then its u16), ``LSN << 8 | CT`` and LSA.
The agent's driver (vehicle_agents/sensors/ydlidar.py) parses exactly these bytes.

Commands go the other way as ``A5 <cmd>``: 0x60 starts the scan, 0x65 stops it, 0x91 asks
for the health. A real T-mini Pro idles after power-up until it gets 0x60 (YDLidar-SDK's
driver sends stop, health, then start), and answers a command with a response
descriptor: ``A5 5A | u32 (length in bits 0..29, mode in bits 30..31: 0 one answer, 1
continuous) | type``, then the answer: 0x60 gets ``A5 5A 05 00 00 40 81`` and the packets
follow; 0x91 gets ``A5 5A 03 00 00 00 06`` and 3 bytes (status: 0 good, 2 error; then a
u16 error code).
"""

from __future__ import annotations

import struct

from simulator.lidar import Beams

HEADER = 0x55AA
COMMAND = 0xA5
START_SCAN = 0x60
STOP_SCAN = 0x65
GET_HEALTH = 0x91
SCAN_RESPONSE = bytes([0xA5, 0x5A, 0x05, 0x00, 0x00, 0x40, 0x81])
HEALTH_RESPONSE = bytes([0xA5, 0x5A, 0x03, 0x00, 0x00, 0x00, 0x06])
MAX_SAMPLES = 40  # what a T-mini Pro puts in one packet
MAX_DISTANCE_MM = 0x3FFF
RETURN_INTENSITY = 180


def encode_angle(degrees: float) -> int:
    """FSA/LSA: 1/64 degree in bits 15..1; bit 0, the check bit, set as the sensor sets it."""
    return ((round(degrees * 64.0) % (360 * 64)) << 1) | 1


def packet(ct: int, angles_deg: list[float], distances_mm: list[int]) -> bytes:
    """One packet; ``ct`` is the packet type byte (bit 0: the zero packet)."""
    count = len(distances_mm)
    fsa, lsa = encode_angle(angles_deg[0]), encode_angle(angles_deg[-1])
    samples = bytearray()
    checksum = HEADER ^ fsa ^ (count << 8 | ct) ^ lsa
    for distance in distances_mm:
        intensity = RETURN_INTENSITY if distance else 0
        word = (min(distance, MAX_DISTANCE_MM) << 2) | (intensity >> 8)
        samples.append(intensity & 0xFF)
        samples += struct.pack("<H", word)
        checksum ^= (intensity & 0xFF) ^ word
    return struct.pack("<HBBHHH", HEADER, ct, count, fsa, lsa, checksum) + bytes(samples)


def encode_beams(beams: Beams, rate_hz: float) -> bytes:
    """The packets for these beams: a zero packet where a turn starts, then packets of up
    to MAX_SAMPLES consecutive samples, never across a turn."""
    zero_ct = (min(127, round(rate_hz * 10.0)) << 1) | 1
    out = bytearray()
    index = beams.index.tolist()
    angles = beams.angle_deg.tolist()
    distances = [round(r * 1000.0) for r in beams.range_m.tolist()]
    start = 0
    n = len(index)
    while start < n:
        if index[start] == 0:
            out += packet(zero_ct, angles[start : start + 1], distances[start : start + 1])
            start += 1
            continue
        end = start + 1
        while end < n and end - start < MAX_SAMPLES and index[end] != 0:
            end += 1
        out += packet(0, angles[start:end], distances[start:end])
        start = end
    return bytes(out)


def health(status: int = 0, error_code: int = 0) -> bytes:
    """The answer to GET_HEALTH: its descriptor and 3 bytes."""
    return HEALTH_RESPONSE + struct.pack("<BH", status, error_code)
