"""A spinning 2-D LIDAR (modelled on the YDLIDAR T-mini Pro) that ray-casts the world.

The head turns at ``rate_hz`` and takes ``beams`` samples per turn, evenly in time, so
each beam is measured at its own instant from the vehicle's pose at that instant: a
vehicle moving or turning during a rotation gets a skewed scan, as a real one does. Poses
between physics steps are interpolated linearly (attitude too: the steps are 20 ms apart).

Angles follow the sensor's own convention: degrees clockwise seen from above, from the
sensor's forward mark, which is mounted along the vehicle's nose at its centre.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from simulator.world.obstacles import Array, World


@dataclass(frozen=True)
class LidarSpec:
    rate_hz: float = 10.0  # T-mini Pro: 6-12 Hz
    beams: int = 720  # per turn: 0.5 degrees at 10 Hz
    min_range_m: float = 0.12
    max_range_m: float = 12.0
    noise_sigma_m: float = 0.02
    dropout: float = 0.01  # share of beams with no return whatever they point at

    def __post_init__(self) -> None:
        if not 5.0 <= self.rate_hz <= 12.0:
            raise ValueError(f"LIDAR rate must be 5..12 Hz, got {self.rate_hz}")
        if not 36 <= self.beams <= 4000:
            raise ValueError(f"LIDAR beams per turn must be 36..4000, got {self.beams}")
        if not 0.0 <= self.dropout < 1.0:
            raise ValueError("LIDAR dropout must be a share, 0 <= x < 1")


@dataclass(frozen=True)
class Pose:
    """Where the sensor is: metres east/north/up of the origin, radians of attitude
    (yaw clockwise from north)."""

    time_s: float
    east: float
    north: float
    up: float
    roll: float
    pitch: float
    yaw: float


@dataclass(frozen=True)
class Beams:
    """Samples measured since the last call: the beam number within its turn, the turn
    it belongs to, the clockwise angle in degrees, the range in metres (0: no return) and
    the time it was measured."""

    index: npt.NDArray[np.int64]
    turn: npt.NDArray[np.int64]
    angle_deg: Array
    range_m: Array
    time_s: Array


def _wrap_pi(angle: Array) -> Array:
    return np.asarray((angle + math.pi) % (2.0 * math.pi) - math.pi, dtype=np.float64)


class Lidar:
    """Call `advance` with each new physics pose; it returns the beams measured up to it."""

    def __init__(self, world: World, spec: LidarSpec | None = None, seed: int = 0) -> None:
        self.world = world
        self.spec = spec or LidarSpec()
        self._rng = np.random.default_rng(seed)
        self._last: Pose | None = None
        self._next_beam = 0  # counts beams since the head started, all turns together

    def beam_time(self, number: int) -> float:
        return number / (self.spec.rate_hz * self.spec.beams)

    def advance(self, pose: Pose) -> Beams | None:
        """Beams measured between the previous pose and this one."""
        previous, self._last = self._last, pose
        if previous is None or pose.time_s <= previous.time_s:
            if previous is None:  # the head starts turning now
                self._next_beam = math.ceil(pose.time_s * self.spec.rate_hz * self.spec.beams)
            return None
        spec = self.spec
        per_s = spec.rate_hz * spec.beams
        last = math.floor(pose.time_s * per_s + 1e-9)
        if last < self._next_beam:
            return None
        numbers = np.arange(self._next_beam, last + 1, dtype=np.int64)
        self._next_beam = last + 1
        times = numbers / per_s
        share = np.clip((times - previous.time_s) / (pose.time_s - previous.time_s), 0.0, 1.0)

        def lerp(a: float, b: float) -> Array:
            return np.asarray(a + (b - a) * share, dtype=np.float64)

        east, north, up = (
            lerp(previous.east, pose.east),
            lerp(previous.north, pose.north),
            lerp(previous.up, pose.up),
        )
        roll, pitch = lerp(previous.roll, pose.roll), lerp(previous.pitch, pose.pitch)
        yaw = previous.yaw + _wrap_pi(np.asarray(pose.yaw - previous.yaw)) * share
        index = numbers % spec.beams
        angle_deg = index.astype(np.float64) * (360.0 / spec.beams)
        directions = _beam_directions(np.radians(angle_deg), roll, pitch, yaw)
        origins = np.column_stack([east, north, up])
        true_range = self.world.cast(origins, directions, spec.max_range_m)
        measured = true_range + self._rng.normal(0.0, spec.noise_sigma_m, len(numbers))
        dropped = self._rng.random(len(numbers)) < spec.dropout
        ok = np.isfinite(true_range) & ~dropped & (measured >= spec.min_range_m)
        ok &= measured <= spec.max_range_m
        range_m = np.where(ok, measured, 0.0)
        return Beams(index, numbers // spec.beams, angle_deg, range_m, times)


def _beam_directions(angle_cw: Array, roll: Array, pitch: Array, yaw: Array) -> Array:
    """Unit east/north/up vectors of beams at clockwise body angles, through the body's
    attitude (ZYX Euler: yaw, then pitch, then roll, as MAVLink's ATTITUDE)."""
    # In the body frame (forward, right, down) a beam lies in the sensor's plane.
    bx, by = np.cos(angle_cw), np.sin(angle_cw)
    cr, sr = np.cos(roll), np.sin(roll)
    cp, sp = np.cos(pitch), np.sin(pitch)
    cy, sy = np.cos(yaw), np.sin(yaw)
    # body -> NED, third body axis left out (bz = 0)
    n = cy * cp * bx + (cy * sp * sr - sy * cr) * by
    e = sy * cp * bx + (sy * sp * sr + cy * cr) * by
    d = -sp * bx + cp * sr * by
    return np.column_stack([e, n, -d])
