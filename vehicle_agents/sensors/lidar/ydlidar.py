"""YDLIDAR's serial packets (X2, X4, G-series, T-mini Pro, ...), from YDLIDAR's published
development manuals (X4 "Development Manual", T-mini Pro "User Manual", YDLidar-SDK).

A packet is, little-endian: ``AA 55 | CT | LSN | FSA u16 | LSA u16 | CS u16 | LSN
samples``. ``CT & 1`` marks the zero packet (the start of a turn, one sample); models
that report it put the scan frequency in tenths of a hertz in ``CT >> 1``. Angles are
``(FSA >> 1) / 64`` and ``(LSA >> 1) / 64`` degrees, clockwise, the samples between them
evenly spaced. Samples are 2 bytes on the models without intensity (X2, X4, G4 ...): a
u16 whose value / 4 is the distance in mm; 3 bytes on the intensity models (T-mini Pro):
the intensity byte, then a u16 whose upper 14 bits are the distance in mm. CS is the XOR
of the u16 words: the header, ``LSN << 8 | CT``, FSA, LSA and every sample (an intensity
sample contributes its intensity byte and its u16).

The triangulation models (X2, X4) need the manual's second-level analysis: each sample's
angle gains ``AngCorrect = atan(21.8 * (155.3 - d) / (155.3 * d))`` degrees (0 for d = 0).

Commands are ``A5 <cmd>``: 0x60 starts the scan, 0x65 stops it, 0x90 asks for the device
information, 0x91 for the health. Answers carry the A5 5A descriptor (common.py): the scan
``A5 5A 05 00 00 40 81``, the health type 0x06 (3 bytes), the information 0x04 (20 bytes).
"""

from __future__ import annotations

import math
import struct
from functools import reduce
from operator import xor

from vehicle_agents.sensors.lidar.common import (
    DESCRIPTOR,
    HEALTH_ANSWER,
    INFO_ANSWER,
    MODE_CONTINUOUS,
    MODE_SINGLE,
    Packet,
    StreamParser,
    wrap360,
)

HEADER = b"\xaa\x55"
HEADER_WORD = 0x55AA
HEADER_BYTES = 10
START_SCAN = b"\xa5\x60"
STOP_SCAN = b"\xa5\x65"
GET_INFO = b"\xa5\x90"
GET_HEALTH = b"\xa5\x91"
SCAN_ANSWER = 0x81
# The answers the driver asks for: type -> (mode, payload length)
ANSWERS = {
    SCAN_ANSWER: (MODE_CONTINUOUS, 5),
    HEALTH_ANSWER: (MODE_SINGLE, 3),
    INFO_ANSWER: (MODE_SINGLE, 20),
}
LOCK_AFTER = 3  # packets of one sample size in a row before an auto parser stops trying the other
MODEL_NAMES = {4: "S4", 5: "G4", 6: "X4", 8: "F4Pro", 13: "G2"}
_HEAD = struct.Struct("<HBBHHH")
_DEG = 180.0 / math.pi


def _model_name(info: bytes) -> str | None:
    return MODEL_NAMES.get(info[0])


def intercept_correction(distance_mm: int) -> float:
    """The X2/X4 manual's AngCorrect, in degrees, for a sample at this distance."""
    if distance_mm == 0:
        return 0.0
    return math.atan(21.8 * (155.3 - distance_mm) / (155.3 * distance_mm)) * _DEG


def checksum(ct: int, count: int, fsa: int, lsa: int, body: bytes | bytearray, size: int) -> int:
    """CS over a packet whose samples are ``size`` (2 or 3) bytes each."""
    words = HEADER_WORD ^ fsa ^ (count << 8 | ct) ^ lsa
    if size == 3:
        # XOR of the u16 words is (XOR of low bytes) | (XOR of high bytes) << 8.
        words ^= reduce(xor, body[0::3], 0)
        return words ^ reduce(xor, body[1::3], 0) ^ (reduce(xor, body[2::3], 0) << 8)
    return words ^ reduce(xor, body[0::2], 0) ^ (reduce(xor, body[1::2], 0) << 8)


class YdlidarParser(StreamParser):
    """``sample_bytes``: 2 or 3 when the model is known, None to tell from each packet's
    checksum (and keep to one size once it has matched `LOCK_AFTER` packets in a row).
    ``intercept``: apply the X2/X4 angle correction."""

    def __init__(self, sample_bytes: int | None = 3, intercept: bool = False) -> None:
        super().__init__()
        if sample_bytes not in (2, 3, None):
            raise ValueError(f"YDLIDAR samples are 2 or 3 bytes, not {sample_bytes}")
        self.sample_bytes = sample_bytes
        self.intercept = intercept
        self._locked = sample_bytes is not None
        self._streak: tuple[int, int] = (0, 0)

    def _parse(self, buffer: bytearray, out: list[Packet]) -> int:
        start = 0
        size = len(buffer)
        while True:
            at = buffer.find(HEADER, start)
            answer = buffer.find(DESCRIPTOR, start, None if at < 0 else at)
            if answer >= 0:
                self.skip(answer - start)
                found = self.answer(buffer, answer, ANSWERS, _model_name)
                if found is None:  # not all here yet
                    return answer
                taken = found[0]
                if taken == 0:  # not an answer we know: skip its marker
                    self.skip(2, "unknown_answer_bytes")
                    start = answer + 2
                else:
                    start = answer + taken
                continue
            if at < 0:
                # keep a trailing 0xAA or 0xA5: it may be the first half of a header
                keep = 1 if size > start and buffer[-1] in (0xAA, 0xA5) else 0
                self.skip(size - start - keep)
                return size - keep
            self.skip(at - start)
            if size - at < HEADER_BYTES:
                return at
            _, ct, count, fsa, lsa, cs = _HEAD.unpack_from(buffer, at)
            if count == 0 or not (fsa & 1 and lsa & 1):  # the check bits are always set
                self.skip(2, "bad_header_bytes")
                start = at + 2
                continue
            sample = self._sample_size(buffer, at, ct, count, fsa, lsa, cs)
            if sample is None:
                return at
            if sample == 0:  # a corrupt packet, or a header pattern inside samples
                self.stats.drops["bad_checksum"] += 1
                start = at + 2
                continue
            end = at + HEADER_BYTES + count * sample
            out.append(self._packet(ct, count, fsa, lsa, buffer[at + HEADER_BYTES : end], sample))
            start = end

    def _sample_size(
        self, buffer: bytearray, at: int, ct: int, count: int, fsa: int, lsa: int, cs: int
    ) -> int | None:
        """The sample size whose checksum matches (0: none does), None until enough bytes
        are here to tell."""
        body = at + HEADER_BYTES
        sizes = (self.sample_bytes,) if self._locked else (2, 3)
        for size in sizes:
            assert size is not None
            end = body + count * size
            if len(buffer) < end:
                return None
            if checksum(ct, count, fsa, lsa, buffer[body:end], size) == cs:
                self._learn(size)
                return size
        return 0

    def _learn(self, size: int) -> None:
        if self._locked:
            return
        run = self._streak[1] + 1 if self._streak[0] == size else 1
        self._streak = (size, run)
        if run >= LOCK_AFTER:
            self.sample_bytes = size
            self._locked = True

    def _packet(
        self, ct: int, count: int, fsa: int, lsa: int, body: bytearray, sample: int
    ) -> Packet:
        first = (fsa >> 1) / 64.0
        span = (lsa >> 1) / 64.0 - first
        if span < 0.0:
            span += 360.0
        step = span / (count - 1) if count > 1 else 0.0
        if sample == 3:
            distances = [(lo | hi << 8) >> 2 for lo, hi in zip(body[1::3], body[2::3], strict=True)]
        else:
            distances = [(lo | hi << 8) >> 2 for lo, hi in zip(body[0::2], body[1::2], strict=True)]
        if self.intercept:
            angles = [
                wrap360(first + i * step + intercept_correction(d)) for i, d in enumerate(distances)
            ]
        else:
            angles = [(first + i * step) % 360.0 for i in range(count)]
        zero = bool(ct & 0x01)
        hz = (ct >> 1) / 10.0 if zero and ct >> 1 else None
        return Packet(zero, hz, angles, distances)
