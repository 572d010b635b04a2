"""What the simulated LIDAR's wire formats share: the encoder and command-reader shapes
`simulator/outputs/lidar.py` drives, the A5 5A answer descriptor (Slamtec and YDLIDAR),
and the range table that lets a format with an angle correction be spoken truthfully.

The formats, by the name `gcs sim --lidar-format` takes (each module documents its bytes):
``ydlidar`` (T-mini Pro, 3-byte samples), ``ydlidar-x4`` (X2/X4: 2-byte samples whose
angles need the manual's intercept correction), ``ydlidar-g4`` (2-byte samples, no
correction), ``rplidar`` / ``rplidar-express`` / ``rplidar-dense`` / ``rplidar-ultra``
(a Slamtec sensor whose express scan answers with that capsule; its standard scan is the
same on all) and ``ld06`` (LDROBOT LD06, LD19 and STL-27L: one format).
"""

from __future__ import annotations

import struct
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Protocol

if TYPE_CHECKING:  # numpy is imported only by a simulator that has a LIDAR (config reads this)
    from simulator.sensors.lidar import Beams

LIDAR_FORMATS = (
    "ydlidar",
    "ydlidar-x4",
    "ydlidar-g4",
    "rplidar",
    "rplidar-express",
    "rplidar-dense",
    "rplidar-ultra",
    "ld06",
)


class Encoder(Protocol):
    def encode(self, beams: Beams, rate_hz: float) -> bytes: ...


@dataclass(frozen=True)
class Start:
    """The client started a scan: ``reply`` first, then the samples of ``mode``."""

    mode: str
    reply: bytes


@dataclass(frozen=True)
class Stop:
    pass


@dataclass(frozen=True)
class Reply:
    data: bytes


Action = Start | Stop | Reply


class CommandReader(Protocol):
    def feed(self, data: bytes) -> list[Action]: ...


@dataclass(frozen=True)
class WireFormat:
    """A format: how each scan mode encodes, how commands are read, and whether the
    sensor sends without being asked (``streams`` names the mode it sends)."""

    encoders: dict[str, Callable[[int], Encoder]]  # mode -> factory(beams per turn)
    commands: Callable[[], CommandReader]
    streams: str | None = None


REQUEST = 0xA5  # both Slamtec and YDLIDAR requests start with it


def split_requests(
    pending: bytes, has_payload: Callable[[int], bool]
) -> tuple[list[tuple[int, bytes]], bytes]:
    """The whole ``A5 <cmd>`` requests at the start of ``pending`` as (command, payload),
    and the bytes left for later. A command for which ``has_payload`` is true is followed
    by its size, the payload and an XOR checksum of all before it; one whose checksum
    fails is dropped, and bytes that start no request are skipped, as a sensor does."""
    requests: list[tuple[int, bytes]] = []
    while len(pending) >= 2:
        if pending[0] != REQUEST:
            pending = pending[1:]
            continue
        command = pending[1]
        if not has_payload(command):
            requests.append((command, b""))
            pending = pending[2:]
            continue
        if len(pending) < 3 or len(pending) < 4 + pending[2]:
            break
        size = pending[2]
        check = 0
        for byte in pending[: 3 + size]:
            check ^= byte
        if check != pending[3 + size]:
            pending = pending[1:]
            continue
        requests.append((command, pending[3 : 3 + size]))
        pending = pending[4 + size :]
    return requests, pending


def descriptor(length: int, mode: int, kind: int) -> bytes:
    """A5 5A, u32 length | mode << 30, type."""
    return b"\xa5\x5a" + struct.pack("<IB", length | mode << 30, kind)


TYPICAL_MM = 2000


class RangeTable:
    """The latest range of every beam of a turn, for formats whose decoder moves each
    sample's angle by an amount that depends on its range (YDLIDAR X4's intercept
    correction, Slamtec's ultra capsules). The sensor sends evenly spaced nominal angles;
    the sample at nominal angle a must hold the range seen at a + shift(range), which is
    found by iterating from the beam at a (the shift changes slowly with range); a
    sample for which no range is consistent is sent as no return."""

    def __init__(self, beams: int) -> None:
        self.ranges = [0] * beams
        self._step = 360.0 / beams

    def update(self, index: list[int], distances_mm: list[int]) -> None:
        for i, distance in zip(index, distances_mm, strict=True):
            self.ranges[i] = distance

    def solve(self, angle_deg: float, shift: Callable[[int], float]) -> int:
        """The range for the sample at nominal ``angle_deg``: one whose shifted angle
        points at a beam of that range. Tried from the beam at the nominal angle and from
        the beam a typical range's shift away (from a no-return beam alone, "no return"
        would be trivially consistent); a sample for which no range is consistent (an
        object's edge) is sent as no return."""
        beams = len(self.ranges)
        for start in (angle_deg, angle_deg + shift(TYPICAL_MM)):
            distance = self.ranges[round(start / self._step) % beams]
            for _ in range(4):
                found = self.ranges[round((angle_deg + shift(distance)) / self._step) % beams]
                if found == distance:
                    if distance:
                        return distance
                    break
                distance = found
        return 0


def millimetres(beams: Beams) -> list[int]:
    return [round(r * 1000.0) for r in beams.range_m.tolist()]


def degrees_q(angle: float, scale: int) -> int:
    """An angle in units of 1/scale degree, in [0, 360 * scale)."""
    return round(angle * scale) % (360 * scale)
