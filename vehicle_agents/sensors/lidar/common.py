"""What every serial LIDAR parser shares: the packet it yields, the drop counters, the
response descriptor that Slamtec and YDLIDAR both use, and the buffer discipline.

Every parser follows one contract: `feed` takes whatever bytes arrived (split or merged
anyhow), returns the whole packets decoded so far, keeps the rest for the next call,
and never raises. A byte that cannot start anything valid is skipped and counted; a
packet whose checksum fails is counted and the search resumes one byte after its start,
so a cut, a corrupted byte or a header pattern inside samples costs at most that packet.

Angles are degrees clockwise seen from above (all three families turn clockwise), from
the sensor's zero mark; distances are millimetres, 0 for no return.
"""

from __future__ import annotations

import logging
import struct
from collections import Counter
from collections.abc import Callable
from dataclasses import dataclass, field

log = logging.getLogger(__name__)

MAX_BUFFER = 64 * 1024  # more than this unparsed is garbage: keep the tail only
KEEP_TAIL = 256  # what is kept of an overflowing buffer: more than any packet

# Slamtec and YDLIDAR answer a command with the same descriptor: A5 5A, a little-endian
# u32 whose bits 0..29 are the answer's length and bits 30..31 its mode (0: one answer,
# 1: the answer repeats until stopped, as a scan does), then the answer's type byte.
DESCRIPTOR = b"\xa5\x5a"
DESCRIPTOR_BYTES = 7
MODE_SINGLE = 0
MODE_CONTINUOUS = 1
INFO_ANSWER = 0x04  # GET_INFO's answer (both families): 20 bytes
HEALTH_ANSWER = 0x06  # GET_HEALTH's answer (both families): 3 bytes
_DESCRIPTOR = struct.Struct("<IB")


@dataclass(frozen=True, slots=True)
class Packet:
    """Consecutive samples: clockwise angles (degrees) and distances (mm, 0 for no
    return). ``zero`` marks the first packet of a new turn; ``scan_hz`` is the turn rate
    when the sensor says it."""

    zero: bool
    scan_hz: float | None
    angles_deg: list[float]
    distances_mm: list[int]


@dataclass(frozen=True, slots=True)
class Health:
    """The answer to GET_HEALTH: status 0 is good, 1 a warning, 2 an error."""

    status: int
    error_code: int

    @property
    def text(self) -> str:
        name = {0: "good", 1: "warning", 2: "error"}.get(self.status, f"status {self.status}")
        return name if not self.error_code else f"{name} (error code {self.error_code:#06x})"


@dataclass(frozen=True, slots=True)
class DeviceInfo:
    """The answer to GET_INFO (both Slamtec and YDLIDAR: 20 bytes)."""

    model: int
    firmware: str
    hardware: int
    serial: str
    name: str  # the model's name where the byte is one we know, else its number


@dataclass
class ParserStats:
    """What a parser decoded and what it threw away, by reason."""

    packets: int = 0
    points: int = 0
    responses: int = 0  # answers to the driver's commands
    drops: Counter[str] = field(default_factory=Counter)

    @property
    def skipped_bytes(self) -> int:
        """Bytes thrown away outside a packet: noise, lost starts, unknown answers."""
        return sum(n for reason, n in self.drops.items() if reason.endswith("_bytes"))

    def as_dict(self) -> dict[str, int]:
        counts = {"packets": self.packets, "points": self.points, "responses": self.responses}
        counts.update({f"dropped_{reason}": n for reason, n in sorted(self.drops.items())})
        return counts


def descriptor_at(buffer: bytearray, at: int) -> tuple[int, int, int] | None:
    """(length, mode, type) of the descriptor at ``at``; None until all 7 bytes are here.
    The caller checks that ``buffer[at:at+2]`` is A5 5A."""
    if len(buffer) - at < DESCRIPTOR_BYTES:
        return None
    word, kind = _DESCRIPTOR.unpack_from(buffer, at + 2)
    return word & 0x3FFFFFFF, word >> 30, kind


def device_info(payload: bytes, name: str | None) -> DeviceInfo:
    """GET_INFO's 20 bytes: model, firmware minor then major, hardware, 16-byte serial.
    (YDLIDAR's firmware u16 has the same layout: minor in the low byte.)"""
    model, minor, major, hardware = payload[0], payload[1], payload[2], payload[3]
    return DeviceInfo(
        model=model,
        firmware=f"{major}.{minor:02d}",
        hardware=hardware,
        serial=payload[4:20].hex().upper(),
        name=name or f"model {model:#04x}",
    )


def wrap360(angle: float) -> float:
    """An angle in [0, 360): Python's ``-1e-15 % 360.0`` is 360.0."""
    angle %= 360.0
    return 0.0 if angle >= 360.0 else angle


class StreamParser:
    """The buffer and the never-raise guard around a family's `_parse`."""

    def __init__(self) -> None:
        self._buffer = bytearray()
        self.stats = ParserStats()
        self.health: Health | None = None
        self.info: DeviceInfo | None = None

    def feed(self, data: bytes) -> list[Packet]:
        """Every whole packet in the bytes received so far; the rest waits for more."""
        buffer = self._buffer
        buffer += data
        packets: list[Packet] = []
        try:
            consumed = self._parse(buffer, packets)
        except Exception:  # a decoder bug must cost bytes, never the relay: counted, logged
            log.exception("LIDAR parser failed on %d buffered bytes; dropped", len(buffer))
            self.stats.drops["parser_error"] += 1
            consumed = len(buffer)
        del buffer[:consumed]
        if len(buffer) > MAX_BUFFER:
            self.stats.drops["overflow_bytes"] += len(buffer) - KEEP_TAIL
            del buffer[:-KEEP_TAIL]
        for packet in packets:
            self.stats.points += len(packet.distances_mm)
        self.stats.packets += len(packets)
        return packets

    def _parse(self, buffer: bytearray, out: list[Packet]) -> int:
        """Append the packets at the start of ``buffer`` to ``out``; the bytes used."""
        raise NotImplementedError

    def answer(
        self,
        buffer: bytearray,
        at: int,
        answers: dict[int, tuple[int, int]],
        name_of: Callable[[bytes], str | None],
    ) -> tuple[int, int] | None:
        """The command answer whose A5 5A is at ``at``: (bytes it takes, its type), 0
        bytes if it is none of ``answers`` (type -> (mode, length)); None until all of it
        is here. A health or information answer is kept (``name_of`` names the model
        from the information's 20 bytes)."""
        head = descriptor_at(buffer, at)
        if head is None:
            return None
        length, mode, kind = head
        if answers.get(kind) != (mode, length):
            return 0, kind
        payload = at + DESCRIPTOR_BYTES
        size = DESCRIPTOR_BYTES + (length if mode == MODE_SINGLE else 0)
        if len(buffer) - at < size:
            return None
        if kind == HEALTH_ANSWER:
            status, code = struct.unpack_from("<BH", buffer, payload)
            self.health = Health(status, code)
        elif kind == INFO_ANSWER:
            info = bytes(buffer[payload : payload + 20])
            self.info = device_info(info, name_of(info))
        self.stats.responses += 1
        return size, kind

    def skip(self, count: int, reason: str = "noise_bytes") -> None:
        if count > 0:
            self.stats.drops[reason] += count


class TurnSplitter:
    """For formats without a start-of-turn flag (LDROBOT, Slamtec's capsules): a turn
    starts where the angle falls back by more than half a turn from the sample before."""

    def __init__(self) -> None:
        self._last: float | None = None

    def reset(self) -> None:
        self._last = None

    def split(
        self, angles: list[float], distances: list[int], scan_hz: float | None, out: list[Packet]
    ) -> None:
        start = 0
        zero = False
        last = self._last
        for i, angle in enumerate(angles):
            if last is not None and angle < last - 180.0:
                if i > start:
                    out.append(Packet(zero, scan_hz, angles[start:i], distances[start:i]))
                start = i
                zero = True
            last = angle
        if start < len(angles):
            out.append(Packet(zero, scan_hz, angles[start:], distances[start:]))
        self._last = last
