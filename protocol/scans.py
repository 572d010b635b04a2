"""The binary scan frame: one 2-D LIDAR turn, as it travels agent -> hub -> subscribers.

Scans are the one binary message on the WebSockets (every other message is JSON text in
`protocol.messages`): a WebSocket binary frame holding exactly one scan. Ranges are
quantised to ``range_scale`` metres (1 mm) in uint16, 0 meaning no return, so a 720-beam
turn is 1,440 bytes of ranges behind a fixed header of `HEADER_BYTES`: 1,580 bytes on the
wire, under the 2 KB bar (tests/unit/test_scan_frame.py).

Layout, little-endian, version 1 (`SCAN_HEADER_FIELDS` lists it for the schema)::

    magic "GSCN" | version u8 | flags u8 | beams u16 | seq u64
    sensor_time_us u64   the flight controller's clock (time since boot) at the first beam
    utc_time f64         the agent's UTC estimate of the first beam, Unix seconds
    duration_s f32       first beam to the end of the turn (beams are evenly spaced in time)
    angle_min f32        radians, counter-clockwise from the sensor's forward axis (REP 103)
    angle_increment f32  radians between beams; negative for a clockwise head (YDLIDAR)
    range_scale f32      metres per range unit
    range_max_m f32      the sensor's maximum: no range beyond it is stored
    pose at the first beam, then at the end of the turn, each:
        lat f64, lon f64 (degrees), alt_msl f32 (m), roll f32, pitch f32, yaw f32
        (radians; yaw clockwise from north, as MAVLink's ATTITUDE)
    mount: forward, right, down f32 (metres from the vehicle's centre), roll, pitch,
        yaw f32 (radians, from the body's axes to the sensor's)
    ranges u16 x beams

The two poses are interpolated by the agent from the flight controller's own timestamps
(GLOBAL_POSITION_INT and ATTITUDE at `sensor_time_us` and at the turn's end); a reader
interpolates between them per beam, which undoes the skew of a scan taken while moving.

Delivery (docs/protocol.md): the live path carries the newest scan only, never a backlog;
the store gets every scan the agent kept.
"""

from __future__ import annotations

import math
import struct
import sys
from array import array
from dataclasses import dataclass, field
from typing import Final

SCAN_MAGIC: Final = b"GSCN"
SCAN_VERSION: Final = 1
FLAG_REPLAYED: Final = 0x01  # from the agent's budget after an outage, not live
MAX_BEAMS: Final = 8192
MAX_RANGE_M: Final = 100.0
NO_RETURN: Final = 0

_HEAD = struct.Struct("<4sBBHQQdfffff")
_POSE = struct.Struct("<ddffff")
_MOUNT = struct.Struct("<ffffff")
HEADER_BYTES: Final = _HEAD.size + 2 * _POSE.size + _MOUNT.size
MAX_SCAN_BYTES: Final = HEADER_BYTES + 2 * MAX_BEAMS

_POSE_FIELDS = (
    ("lat", "f64"),
    ("lon", "f64"),
    ("alt_msl", "f32"),
    ("roll", "f32"),
    ("pitch", "f32"),
    ("yaw", "f32"),
)
SCAN_HEADER_FIELDS: Final = [
    ("magic", "4s"),
    ("version", "u8"),
    ("flags", "u8"),
    ("beams", "u16"),
    ("seq", "u64"),
    ("sensor_time_us", "u64"),
    ("utc_time", "f64"),
    ("duration_s", "f32"),
    ("angle_min", "f32"),
    ("angle_increment", "f32"),
    ("range_scale", "f32"),
    ("range_max_m", "f32"),
    *((f"pose_{when}_{name}", kind) for when in ("start", "end") for name, kind in _POSE_FIELDS),
    *((f"mount_{name}", "f32") for name in ("forward", "right", "down", "roll", "pitch", "yaw")),
    ("ranges", "u16[beams]"),
]


class ScanFrameError(ValueError):
    """A scan frame that cannot be used; the message names the field and the rule."""


@dataclass(frozen=True, slots=True)
class ScanPose:
    lat: float
    lon: float
    alt_msl: float
    roll: float = 0.0
    pitch: float = 0.0
    yaw: float = 0.0


@dataclass(frozen=True, slots=True)
class Mount:
    """Where the sensor sits on the vehicle: metres forward, right and down of its centre,
    and the rotation from the body's axes to the sensor's (radians)."""

    forward: float = 0.0
    right: float = 0.0
    down: float = 0.0
    roll: float = 0.0
    pitch: float = 0.0
    yaw: float = 0.0


@dataclass(frozen=True, slots=True)
class ScanFrame:
    seq: int
    sensor_time_us: int
    utc_time: float
    duration_s: float
    angle_min: float
    angle_increment: float
    range_max_m: float
    pose_start: ScanPose
    pose_end: ScanPose
    ranges: array[int]  # typecode "H": units of range_scale, NO_RETURN for none
    range_scale: float = 0.001
    mount: Mount = field(default_factory=Mount)
    flags: int = 0

    @property
    def beams(self) -> int:
        return len(self.ranges)

    @property
    def replayed(self) -> bool:
        return bool(self.flags & FLAG_REPLAYED)


def quantise(
    ranges_m: list[float], range_scale: float, range_max_m: float
) -> tuple[array[int], int]:
    """uint16 ranges from metres; NaN, infinite, zero, negative and beyond-maximum ranges
    become NO_RETURN. Returns the ranges and how many were cleaned that way."""
    top = min(range_max_m, 65535 * range_scale)
    out = array("H", bytes(2 * len(ranges_m)))
    cleaned = 0
    for i, value in enumerate(ranges_m):
        if value > 0.0 and value <= top:  # False for NaN
            out[i] = max(1, round(value / range_scale))
        elif value != 0.0:
            cleaned += 1
    return out, cleaned


def encode_scan(frame: ScanFrame) -> bytes:
    """The frame's bytes; raises ScanFrameError for what `decode_scan` would refuse."""
    _check(frame)
    ranges = frame.ranges
    if ranges.typecode != "H":
        raise ScanFrameError("ranges: must be an array of typecode 'H' (uint16)")
    if sys.byteorder != "little":
        ranges = array("H", ranges)
        ranges.byteswap()
    m = frame.mount
    return b"".join(
        (
            _HEAD.pack(
                SCAN_MAGIC,
                SCAN_VERSION,
                frame.flags,
                len(frame.ranges),
                frame.seq,
                frame.sensor_time_us,
                frame.utc_time,
                frame.duration_s,
                frame.angle_min,
                frame.angle_increment,
                frame.range_scale,
                frame.range_max_m,
            ),
            _POSE.pack(*_pose_tuple(frame.pose_start)),
            _POSE.pack(*_pose_tuple(frame.pose_end)),
            _MOUNT.pack(m.forward, m.right, m.down, m.roll, m.pitch, m.yaw),
            ranges.tobytes(),
        )
    )


def with_flags(data: bytes, flags: int) -> bytes:
    """The same frame with other flags (the agent marks a replayed scan)."""
    return data[:5] + bytes([flags]) + data[6:]


def decode_scan(data: bytes) -> ScanFrame:
    """A frame from its bytes, checked field by field (ScanFrameError names the rule)."""
    if len(data) > MAX_SCAN_BYTES:
        raise ScanFrameError(f"frame: {len(data)} bytes is over the limit of {MAX_SCAN_BYTES}")
    if len(data) < HEADER_BYTES:
        raise ScanFrameError(
            f"frame: {len(data)} bytes is shorter than the {HEADER_BYTES}-byte header"
        )
    (
        magic,
        version,
        flags,
        beams,
        seq,
        sensor_us,
        utc,
        duration,
        angle_min,
        increment,
        scale,
        range_max,
    ) = _HEAD.unpack_from(data, 0)
    if magic != SCAN_MAGIC:
        raise ScanFrameError("magic: not a scan frame (expected b'GSCN')")
    if version != SCAN_VERSION:
        raise ScanFrameError(
            f"version: {version} is not supported (this hub speaks {SCAN_VERSION})"
        )
    if len(data) != HEADER_BYTES + 2 * beams:
        raise ScanFrameError(
            f"beams: the header says {beams} beams, the frame holds "
            f"{(len(data) - HEADER_BYTES) / 2:g}"
        )
    offset = _HEAD.size
    start = ScanPose(*_POSE.unpack_from(data, offset))
    end = ScanPose(*_POSE.unpack_from(data, offset + _POSE.size))
    mount = Mount(*_MOUNT.unpack_from(data, offset + 2 * _POSE.size))
    ranges = array("H")
    ranges.frombytes(data[HEADER_BYTES:])
    if sys.byteorder != "little":
        ranges.byteswap()
    frame = ScanFrame(
        seq=seq,
        sensor_time_us=sensor_us,
        utc_time=utc,
        duration_s=duration,
        angle_min=angle_min,
        angle_increment=increment,
        range_max_m=range_max,
        pose_start=start,
        pose_end=end,
        ranges=ranges,
        range_scale=scale,
        mount=mount,
        flags=flags,
    )
    _check(frame)
    return frame


def _pose_tuple(pose: ScanPose) -> tuple[float, ...]:
    return (pose.lat, pose.lon, pose.alt_msl, pose.roll, pose.pitch, pose.yaw)


def _finite(name: str, value: float) -> None:
    if not math.isfinite(value):
        raise ScanFrameError(f"{name}: must be a finite number, got {value}")


def _check(frame: ScanFrame) -> None:
    if not 1 <= len(frame.ranges) <= MAX_BEAMS:
        raise ScanFrameError(f"beams: must be 1..{MAX_BEAMS}, got {len(frame.ranges)}")
    for name in (
        "utc_time",
        "duration_s",
        "angle_min",
        "angle_increment",
        "range_scale",
        "range_max_m",
    ):
        _finite(name, getattr(frame, name))
    if not 0.0 < frame.duration_s <= 1.0:
        raise ScanFrameError(f"duration_s: must be > 0 and <= 1 s, got {frame.duration_s}")
    if not 0.0 < frame.range_scale <= 0.1:
        raise ScanFrameError(f"range_scale: must be > 0 and <= 0.1 m, got {frame.range_scale}")
    if not 0.0 < frame.range_max_m <= MAX_RANGE_M:
        raise ScanFrameError(f"range_max_m: must be > 0 and <= {MAX_RANGE_M:g}")
    if frame.angle_increment == 0.0 or abs(frame.angle_increment * len(frame.ranges)) > (
        2.0 * math.pi + 1e-3
    ):
        raise ScanFrameError("angle_increment: beams must cover at most one turn, and not 0")
    for when, pose in (("pose_start", frame.pose_start), ("pose_end", frame.pose_end)):
        for name, value in zip(
            ("lat", "lon", "alt_msl", "roll", "pitch", "yaw"), _pose_tuple(pose), strict=True
        ):
            _finite(f"{when}.{name}", value)
        if not (-90.0 <= pose.lat <= 90.0 and -180.0 <= pose.lon <= 180.0):
            raise ScanFrameError(f"{when}: latitude/longitude out of range")
    m = frame.mount
    for name in ("forward", "right", "down", "roll", "pitch", "yaw"):
        _finite(f"mount.{name}", getattr(m, name))


CLIENT_SCAN_MAGIC: Final = b"GSCV"


def client_scan_frame(vehicle_id: str, data: bytes) -> bytes:
    """A scan as the hub sends it to a subscriber: ``"GSCV" | id length u8 | vehicle id
    (UTF-8) | the agent's scan frame``."""
    name = vehicle_id.encode()
    if len(name) > 255:
        raise ScanFrameError("vehicle_id: at most 255 bytes")
    return CLIENT_SCAN_MAGIC + bytes([len(name)]) + name + data


def split_client_scan_frame(data: bytes) -> tuple[str, ScanFrame]:
    """The vehicle id and the scan of a subscriber's binary frame."""
    if data[:4] != CLIENT_SCAN_MAGIC or len(data) < 5:
        raise ScanFrameError("magic: not a subscriber's scan frame (expected b'GSCV')")
    size = data[4]
    try:
        vehicle_id = data[5 : 5 + size].decode()
    except UnicodeDecodeError:
        raise ScanFrameError("vehicle_id: not UTF-8") from None
    return vehicle_id, decode_scan(data[5 + size :])


_FIELD_BYTES = {"4s": 4, "u8": 1, "u16": 2, "u64": 8, "f32": 4, "f64": 8}


def scan_frame_schema() -> dict[str, object]:
    """The binary frames' layout as data, exported beside the JSON messages' schema
    (``python -m protocol.messages``): each header field with its type and byte offset."""
    fields: list[dict[str, object]] = []
    offset = 0
    for name, kind in SCAN_HEADER_FIELDS:
        fields.append({"name": name, "type": kind, "offset": offset})
        offset += _FIELD_BYTES.get(kind, 0)
    return {
        "byte_order": "little",
        "magic": SCAN_MAGIC.decode(),
        "version": SCAN_VERSION,
        "header_bytes": HEADER_BYTES,
        "fields": fields,
        "flags": {"replayed": FLAG_REPLAYED},
        "no_return": NO_RETURN,
        "max_beams": MAX_BEAMS,
        "max_bytes": MAX_SCAN_BYTES,
        "to_subscribers": {
            "magic": CLIENT_SCAN_MAGIC.decode(),
            "layout": "magic (4) | vehicle id length u8 | vehicle id (UTF-8) | scan frame",
        },
    }
