"""The flight controller's clock and its recent poses, for stamping scans.

A LIDAR's bytes carry no time: the agent stamps them on arrival (`time.monotonic`). The
flight controller stamps its own messages (``time_boot_ms``), so the agent maps its clock
onto the flight controller's from messages that carry that stamp (ATTITUDE,
GLOBAL_POSITION_INT, SYSTEM_TIME, and TIMESYNC's nanoseconds since boot): a line fitted
through (arrival, stamp) pairs, raised to the least delayed of them, since a message can
arrive late but never early. TIMESYNC is the two-way time protocol, but a round trip
needs the flight controller to answer in time and assumes the two ways take as long;
its stamps are used here as one more one-way sample (the flight controller's own request
carries its clock in ``ts1``, its answer in ``tc1``), and only once they agree with the
streams' clock within `TIMESYNC_AGREE_S`, since a companion computer on the same link
sends TIMESYNC on a clock of its own. The line's
slope is the ratio of the two clocks (1 for a real board; the simulator's sped-up clock
runs faster), so the mapping holds on either.

Poses are kept as the flight controller reported them, by its own stamps, and interpolated
to any instant between two reports: position from GLOBAL_POSITION_INT, attitude from
ATTITUDE.
"""

from __future__ import annotations

import asyncio
import bisect
import contextlib
import math
import time
from collections import deque
from collections.abc import Callable
from typing import Any

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from protocol.scans import ScanPose
from vehicle_agents.sensors.envelope import lower_envelope_slope

CLOCK_WINDOW = 400  # samples: 10-20 s of the streams that carry time_boot_ms
REFIT_EVERY = 20
POSE_WINDOW = 100  # reports of each kind: 10 s at 10 Hz
STAMPED = frozenset({"ATTITUDE", "GLOBAL_POSITION_INT", "SYSTEM_TIME"})
TIMESYNC_AGREE_S = 1.0
TIMESYNC_EVERY_S = 2.0


async def ask_timesync(
    send: Callable[[Any], None],
    every_s: float = TIMESYNC_EVERY_S,
    monotonic_ns: Callable[[], int] = time.monotonic_ns,
) -> None:
    """Ask the flight controller for its clock now and then (TIMESYNC with ``tc1`` 0;
    ArduPilot and PX4 answer with their nanoseconds since boot), for `PoseHistory`."""
    while True:
        with contextlib.suppress(ConnectionError):  # down: the streams' clock waits too
            send(mavlink2.MAVLink_timesync_message(0, monotonic_ns()))
        await asyncio.sleep(every_s)


class FcuClock:
    """Maps the agent's monotonic seconds to the flight controller's seconds since boot."""

    def __init__(self) -> None:
        self._samples: deque[tuple[float, float]] = deque(maxlen=CLOCK_WINDOW)
        self._rate = 1.0
        self._offset: float | None = None
        self._since_fit = 0
        self.reboots = 0

    def add(self, arrived: float, boot_s: float) -> None:
        if self._samples and boot_s < self._samples[-1][1] - 1.0:
            self._samples.clear()  # the flight controller rebooted: its clock started again
            self._offset = None
            self.reboots += 1
        self._samples.append((arrived, boot_s))
        self._since_fit += 1
        if self._offset is None or self._since_fit >= REFIT_EVERY:
            self._fit()
        else:  # a less delayed sample raises the line at once
            self._offset = max(self._offset, boot_s - self._rate * arrived)

    def _fit(self) -> None:
        self._since_fit = 0
        samples = self._samples
        if len(samples) >= 20 and samples[-1][0] - samples[0][0] >= 2.0:
            # arrival as a function of the board's time: delays push it up, never down
            by_board = [(boot, arrived) for arrived, boot in samples]
            per_board_s = lower_envelope_slope(by_board, 1.0 / self._rate)
            if 0.005 < per_board_s < 100.0:
                self._rate = 1.0 / per_board_s
        self._offset = max(b - self._rate * a for a, b in samples)

    @property
    def synced(self) -> bool:
        return self._offset is not None

    def to_fcu(self, monotonic_s: float) -> float:
        assert self._offset is not None
        return self._rate * monotonic_s + self._offset

    def to_monotonic(self, fcu_s: float) -> float:
        assert self._offset is not None
        return (fcu_s - self._offset) / self._rate

    @property
    def rate(self) -> float:
        return self._rate


def _lerp(a: float, b: float, share: float) -> float:
    return a + (b - a) * share


def _lerp_angle(a: float, b: float, share: float) -> float:
    turn = (b - a + math.pi) % (2.0 * math.pi) - math.pi
    return a + turn * share


class PoseHistory:
    """The flight controller's recent positions and attitudes, by its clock."""

    def __init__(self, clock: FcuClock, monotonic: Callable[[], float] = time.monotonic) -> None:
        self.clock = clock
        self._monotonic = monotonic
        self._pos_t: deque[float] = deque(maxlen=POSE_WINDOW)
        self._pos: deque[tuple[float, float, float]] = deque(maxlen=POSE_WINDOW)
        self._att_t: deque[float] = deque(maxlen=POSE_WINDOW)
        self._att: deque[tuple[float, float, float]] = deque(maxlen=POSE_WINDOW)
        self.timesync_ignored = 0  # TIMESYNC on another clock, or before the streams'

    def on_message(self, message: Any) -> None:
        """An FcuLink listener."""
        kind = message.get_type()
        if kind == "TIMESYNC":
            self._timesync(message)
            return
        if kind not in STAMPED:
            return
        boot_s = message.time_boot_ms / 1000.0
        if kind == "SYSTEM_TIME" and boot_s <= 0.0:
            return
        self.clock.add(self._monotonic(), boot_s)
        if kind == "GLOBAL_POSITION_INT":
            self._push(
                self._pos_t,
                self._pos,
                boot_s,
                (message.lat / 1e7, message.lon / 1e7, message.alt / 1000.0),
            )
        elif kind == "ATTITUDE":
            self._push(
                self._att_t,
                self._att,
                boot_s,
                (float(message.roll), float(message.pitch), float(message.yaw)),
            )

    def _timesync(self, message: Any) -> None:
        board_ns = int(message.ts1) if int(message.tc1) == 0 else int(message.tc1)
        arrived = self._monotonic()
        boot_s = board_ns / 1e9
        if not self.clock.synced or abs(self.clock.to_fcu(arrived) - boot_s) > TIMESYNC_AGREE_S:
            self.timesync_ignored += 1
            return
        self.clock.add(arrived, boot_s)

    @staticmethod
    def _push(
        times: deque[float],
        values: deque[tuple[float, float, float]],
        t: float,
        value: tuple[float, float, float],
    ) -> None:
        if times and t < times[-1] - 1.0:  # a reboot: older reports belong to another clock
            times.clear()
            values.clear()
        if times and t <= times[-1]:
            return
        times.append(t)
        values.append(value)

    def latest_time(self) -> float | None:
        """The newest instant both position and attitude are known up to."""
        if not self._pos_t or not self._att_t:
            return None
        return min(self._pos_t[-1], self._att_t[-1])

    def at(self, t: float) -> ScanPose | None:
        """The pose at flight-controller time ``t``, or None outside what is known."""
        position = _interpolate(self._pos_t, self._pos, t, angles=False)
        attitude = _interpolate(self._att_t, self._att, t, angles=True)
        if position is None or attitude is None:
            return None
        return ScanPose(position[0], position[1], position[2], *attitude)


def _interpolate(
    times: deque[float], values: deque[tuple[float, float, float]], t: float, *, angles: bool
) -> tuple[float, float, float] | None:
    if not times or t < times[0] or t > times[-1]:
        return None
    i = bisect.bisect_left(times, t)
    if times[i] == t:
        return values[i]
    t0, t1 = times[i - 1], times[i]
    share = (t - t0) / (t1 - t0)
    a, b = values[i - 1], values[i]
    if angles:
        return (
            _lerp_angle(a[0], b[0], share),
            _lerp_angle(a[1], b[1], share),
            _lerp_angle(a[2], b[2], share),
        )
    return (_lerp(a[0], b[0], share), _lerp(a[1], b[1], share), _lerp(a[2], b[2], share))
