"""A parser for YDLIDAR's serial packets (T-mini Pro and the other intensity models).

The format is YDLIDAR's published one (see simulator/ydlidar_wire.py for the layout). No
maintained Python package parses it from a byte stream: YDLIDAR's own SDK is C++ with
SWIG bindings that open the port themselves (so they cannot read the simulator's socket
or a test's corrupted bytes), and PyLidar3 speaks only the old X4's 2-byte samples and
is unmaintained. This is the ~100 lines that feed on whatever bytes arrive, split or
merged anyhow, and never raise on garbage: it counts what it throws away.

Pure Python (bytes slicing and integer XOR), no numpy: the agent's base install stays
small, and a 10 Hz, 720-sample stream costs well under 1 % of a core (bench/bench_scans.py).
"""

from __future__ import annotations

import struct
from dataclasses import dataclass
from functools import reduce
from operator import xor

HEADER = b"\xaa\x55"
HEADER_WORD = 0x55AA
HEADER_BYTES = 10
SAMPLE_BYTES = 3  # intensity models: intensity, then a u16 of distance << 2
MAX_BUFFER = 64 * 1024  # more than this unparsed is garbage: keep the tail only
_HEAD = struct.Struct("<HBBHHH")


@dataclass(frozen=True, slots=True)
class Packet:
    """One packet: its samples' clockwise angles (degrees) and distances (millimetres,
    0 for no return). ``scan_hz`` is set on a zero packet (the start of a turn) when
    the sensor reports its frequency."""

    zero: bool
    scan_hz: float | None
    angles_deg: list[float]
    distances_mm: list[int]


@dataclass
class ParserStats:
    packets: int = 0
    bad_checksums: int = 0
    skipped_bytes: int = 0  # bytes before a header: noise, or a packet's lost start


class YdlidarParser:
    def __init__(self) -> None:
        self._buffer = bytearray()
        self.stats = ParserStats()

    def feed(self, data: bytes) -> list[Packet]:
        """Every whole packet in the bytes received so far; the rest waits for more."""
        buffer = self._buffer
        buffer += data
        packets: list[Packet] = []
        start = 0
        while True:
            at = buffer.find(HEADER, start)
            if at < 0:
                # keep a trailing 0xAA: it may be the first half of a header
                keep = 1 if buffer.endswith(b"\xaa") else 0
                self.stats.skipped_bytes += len(buffer) - start - keep
                start = len(buffer) - keep
                break
            self.stats.skipped_bytes += at - start
            if len(buffer) - at < HEADER_BYTES:
                start = at
                break
            _, ct, count, fsa, lsa, checksum = _HEAD.unpack_from(buffer, at)
            end = at + HEADER_BYTES + count * SAMPLE_BYTES
            if count == 0:
                self.stats.skipped_bytes += 2
                start = at + 2
                continue
            if len(buffer) < end:
                start = at
                break
            body = bytes(buffer[at + HEADER_BYTES : end])
            if _checksum(ct, count, fsa, lsa, body) != checksum:
                # a corrupt packet, or a header pattern inside samples: resync after it
                self.stats.bad_checksums += 1
                start = at + 2
                continue
            packets.append(_packet(ct, count, fsa, lsa, body))
            self.stats.packets += 1
            start = end
        del buffer[:start]
        if len(buffer) > MAX_BUFFER:
            self.stats.skipped_bytes += len(buffer) - HEADER_BYTES
            del buffer[:-HEADER_BYTES]
        return packets


def _checksum(ct: int, count: int, fsa: int, lsa: int, body: bytes) -> int:
    # XOR of the samples' u16 words is (XOR of low bytes) | (XOR of high bytes) << 8.
    intensities = reduce(xor, body[0::3], 0)
    low = reduce(xor, body[1::3], 0)
    high = reduce(xor, body[2::3], 0)
    return HEADER_WORD ^ fsa ^ (count << 8 | ct) ^ lsa ^ intensities ^ (low | high << 8)


def _packet(ct: int, count: int, fsa: int, lsa: int, body: bytes) -> Packet:
    first = (fsa >> 1) / 64.0
    last = (lsa >> 1) / 64.0
    span = last - first
    if span < 0.0:
        span += 360.0
    step = span / (count - 1) if count > 1 else 0.0
    angles = [(first + i * step) % 360.0 for i in range(count)]
    distances = [(lo | hi << 8) >> 2 for lo, hi in zip(body[1::3], body[2::3], strict=True)]
    zero = bool(ct & 0x01)
    hz = (ct >> 1) / 10.0 if zero and ct >> 1 else None
    return Packet(zero, hz, angles, distances)
