"""A scan's beams as points in the world: east-north-up metres around the site's origin,
and WGS-84.

Each beam is placed from the pose at its own instant: the frame carries the vehicle's pose
at the start and the end of the turn (the agent interpolated both from the flight
controller's own timestamps), and beams are evenly spaced in time between them, so the
pose is interpolated per beam. That undoes the skew of a turn taken while moving or
turning. The sensor's mount (offset and rotation on the body) is applied before the
body's attitude.

Frames, as MAVLink and ROS use them: the sensor's beams are counter-clockwise from its
forward axis (REP 103: x forward, y left, z up); the body is forward-right-down; the
attitude is ZYX Euler (yaw clockwise from north, then pitch, then roll) into
north-east-down; the world is east-north-up on the site's tangent plane.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
from pymap3d.enu import enu2geodetic, geodetic2enu

from common.geodesy import WGS84, LocalFrame
from protocol.scans import ScanFrame

Array = npt.NDArray[np.float64]


@dataclass(frozen=True)
class WorldPoints:
    """Returns of one scan: (n, 3) east/north/up metres from the site origin, and the
    time of each (UTC)."""

    enu: Array
    times: Array

    def __len__(self) -> int:
        return len(self.enu)

    def geodetic(self, site: LocalFrame) -> Array:
        """(n, 3) latitude, longitude (degrees) and altitude (m) of each point."""
        o = site.origin
        lat, lon, alt = enu2geodetic(
            self.enu[:, 0], self.enu[:, 1], self.enu[:, 2], o.lat, o.lon, o.alt, WGS84
        )
        return np.column_stack([lat, lon, alt])


def _rotation(roll: Array, pitch: Array, yaw: Array) -> Array:
    """(n, 3, 3) ZYX Euler rotations (the body's axes into the parent's)."""
    cr, sr = np.cos(roll), np.sin(roll)
    cp, sp = np.cos(pitch), np.sin(pitch)
    cy, sy = np.cos(yaw), np.sin(yaw)
    return np.stack(
        [
            np.stack([cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr], axis=-1),
            np.stack([sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr], axis=-1),
            np.stack([-sp, cp * sr, cp * cr], axis=-1),
        ],
        axis=-2,
    )


def _wrap(angle: float) -> float:
    return float((angle + np.pi) % (2.0 * np.pi) - np.pi)


def world_points(frame: ScanFrame, site: LocalFrame) -> WorldPoints:
    """The frame's returns (ranges of 0 are no return and give no point)."""
    ranges = np.frombuffer(frame.ranges.tobytes(), dtype=np.uint16).astype(np.float64)
    index = np.flatnonzero(ranges)
    r = ranges[index] * frame.range_scale
    share = index / len(ranges)
    angle = frame.angle_min + index * frame.angle_increment
    # In the sensor's own frame (x forward, y left, z up), then as forward-right-down.
    sensor = np.column_stack([r * np.cos(angle), -r * np.sin(angle), np.zeros_like(r)])
    m = frame.mount
    mount = _rotation(np.array(m.roll), np.array(m.pitch), np.array(m.yaw))
    body = sensor @ mount.T + np.array([m.forward, m.right, m.down])
    a, b = frame.pose_start, frame.pose_end
    roll = a.roll + _wrap(b.roll - a.roll) * share
    pitch = a.pitch + _wrap(b.pitch - a.pitch) * share
    yaw = a.yaw + _wrap(b.yaw - a.yaw) * share
    ned = np.einsum("nij,nj->ni", _rotation(roll, pitch, yaw), body)
    start = np.array(site.to_enu(a.lat, a.lon, a.alt_msl))
    end = np.array(site.to_enu(b.lat, b.lon, b.alt_msl))
    origin = start + (end - start) * share[:, None]
    enu = origin + np.column_stack([ned[:, 1], ned[:, 0], -ned[:, 2]])
    times = frame.utc_time + share * frame.duration_s
    return WorldPoints(enu, times)


def in_frame(
    points: WorldPoints,
    site: LocalFrame,
    frame: LocalFrame,
    cell_m: float,
    limit: int,
    above_msl: float | None = None,
) -> tuple[list[float], list[float]]:
    """The points' north and east metres on another tangent plane (a formation's),
    one per ``cell_m`` cell and at most ``limit`` of them (evenly strided when more),
    rounded to the centimetre: what a follower's agent is sent. Points at or below
    ``above_msl`` (metres above mean sea level) are left out: a tilted scan's beams that
    reach the ground are not obstacles."""
    if not len(points):
        return [], []
    geo = points.geodetic(site)
    if above_msl is not None:
        geo = geo[geo[:, 2] > above_msl]
        if not len(geo):
            return [], []
    o = frame.origin
    east, north, _ = geodetic2enu(geo[:, 0], geo[:, 1], geo[:, 2], o.lat, o.lon, o.alt, WGS84)
    ne = np.column_stack([np.asarray(north, dtype=np.float64), np.asarray(east, dtype=np.float64)])
    _, first = np.unique(np.floor(ne / cell_m).astype(np.int64), axis=0, return_index=True)
    kept = ne[np.sort(first)]
    if len(kept) > limit:
        kept = kept[np.linspace(0, len(kept) - 1, limit).astype(np.int64)]
    kept = np.round(kept, 2)
    return kept[:, 0].tolist(), kept[:, 1].tolist()
