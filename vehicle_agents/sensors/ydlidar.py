"""A parser for YDLIDAR's serial packets (T-mini Pro and the other intensity models).

The format is YDLIDAR's published one (see simulator/ydlidar_wire.py for the layout). No
maintained Python package parses it from a byte stream: YDLIDAR's own SDK is C++ with
SWIG bindings that open the port themselves (so they cannot read the simulator's socket
or a test's corrupted bytes), and PyLidar3 speaks only the old X4's 2-byte samples and
is unmaintained (neither is on PyPI as a maintained package; the SDK is built from
source). Slamtec's RPLIDAR does have a maintained reader (adafruit-circuitpython-rplidar),
but its format is another, and the seed experiment's sensor is a YDLIDAR T-mini Pro.
This is the ~150 lines that feed on whatever bytes arrive, split or
merged anyhow, and never raise on garbage: it counts what it throws away. It also reads
the answers to the driver's commands (start, health) that come before the packets.

Pure Python (bytes slicing and integer XOR), no numpy: the agent's base install stays
small, and a 10 Hz, 720-sample stream costs well under 1 % of a core (bench/bench_scans.py).
"""

from __future__ import annotations

import struct
from dataclasses import dataclass
from functools import reduce
from operator import xor

HEADER = b"\xaa\x55"
RESPONSE = b"\xa5\x5a"  # a command's answer: descriptor, then (one-shot answers) payload
RESPONSE_BYTES = 7
# The answers the driver asks for: type -> (mode, payload length); mode 1 is continuous
# (the scan packets follow, with their own headers), 0 one answer of that length.
RESPONSES = {0x81: (1, 5), 0x06: (0, 3)}
HEALTH = 0x06
START_SCAN = b"\xa5\x60"
STOP_SCAN = b"\xa5\x65"
GET_HEALTH = b"\xa5\x91"
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
    responses: int = 0  # answers to the driver's commands


@dataclass(frozen=True, slots=True)
class Health:
    """The sensor's answer to GET_HEALTH: status 0 is good, 1 a warning, 2 an error."""

    status: int
    error_code: int


class YdlidarParser:
    def __init__(self) -> None:
        self._buffer = bytearray()
        self.stats = ParserStats()
        self.health: Health | None = None

    def feed(self, data: bytes) -> list[Packet]:
        """Every whole packet in the bytes received so far; the rest waits for more."""
        buffer = self._buffer
        buffer += data
        packets: list[Packet] = []
        start = 0
        while True:
            at = buffer.find(HEADER, start)
            answer = buffer.find(RESPONSE, start, None if at < 0 else at)
            if answer >= 0:
                self.stats.skipped_bytes += answer - start
                taken = self._response(buffer, answer)
                if taken is None:  # not all here yet
                    start = answer
                    break
                start = answer + (taken or 2)  # 0: not an answer we know, skip its marker
                self.stats.skipped_bytes += 0 if taken else 2
                continue
            if at < 0:
                # keep a trailing 0xAA or 0xA5: it may be the first half of a header
                keep = 1 if buffer and buffer[-1] in (0xAA, 0xA5) else 0
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

    def _response(self, buffer: bytearray, at: int) -> int | None:
        """The length of the command answer at ``at`` (0 if it is none the driver asks
        for), or None until all of it is here."""
        if len(buffer) - at < RESPONSE_BYTES:
            return None
        word, kind = struct.unpack_from("<IB", buffer, at + 2)
        mode, length = word >> 30, word & 0x3FFFFFFF
        if RESPONSES.get(kind) != (mode, length):
            return 0
        size = RESPONSE_BYTES + (length if mode == 0 else 0)
        if len(buffer) - at < size:
            return None
        if kind == HEALTH:
            status, code = struct.unpack_from("<BH", buffer, at + RESPONSE_BYTES)
            self.health = Health(status, code)
        self.stats.responses += 1
        return size


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
