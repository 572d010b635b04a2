"""A serial LIDAR's packets into whole turns, each beam timed on the agent's clock."""

from __future__ import annotations

import math
from array import array
from collections import deque
from dataclasses import dataclass, field

from vehicle_agents.sensors.envelope import lower_envelope_slope
from vehicle_agents.sensors.lidar.common import Packet
from vehicle_agents.sensors.turn import Turn

DEFAULT_PERIOD_S = 0.1
CLOCK_WINDOW = 800  # packets: a few seconds of a T-mini Pro at 10 Hz
REFIT_EVERY = 50


class SensorClock:
    """When each beam was measured, on the agent's clock.

    The head samples at a steady rate, so beam number ``g`` (counted over all turns) was
    measured at ``origin + g * spacing``. Each packet, stamped on arrival, is a sample of
    that line, late by its trip (the UART, the OS, the event loop) but never early: the
    spacing is fitted through the samples of the last few seconds, and the line is lowered
    to the least delayed of them. One delayed read then moves nothing, and the start of a
    turn comes out to within the best trip time of the window, not of that one turn.
    """

    def __init__(self, spacing_s: float) -> None:
        self._samples: deque[tuple[int, float]] = deque(maxlen=CLOCK_WINDOW)
        self.reset(spacing_s)

    def reset(self, spacing_s: float) -> None:
        """Start again from the sensor's stated rate (before any turn was timed)."""
        self.spacing_s = spacing_s
        self._samples.clear()
        self._origin: float | None = None
        self._since_fit = 0

    def add(self, beam: int, arrived: float) -> None:
        self._samples.append((beam, arrived))
        self._since_fit += 1
        if self._origin is None or self._since_fit >= REFIT_EVERY:
            self._fit()
        else:
            self._origin = min(self._origin, arrived - beam * self.spacing_s)

    def _fit(self) -> None:
        self._since_fit = 0
        samples = list(self._samples)
        if len(samples) >= 20 and samples[-1][0] > samples[0][0]:
            self.spacing_s = lower_envelope_slope(samples, self.spacing_s)
        self._origin = min(t - g * self.spacing_s for g, t in samples)

    def time_of(self, beam: int) -> float:
        assert self._origin is not None
        return self._origin + beam * self.spacing_s


@dataclass
class TurnAssembler:
    """Packets into turns on a fixed grid of ``resolution_deg`` beams, each turn
    timed by a `SensorClock` (the sensor's own frequency only until it has samples)."""

    resolution_deg: float = 0.5
    range_max_m: float = 12.0
    _ranges: array[int] | None = None
    _turn: int = -1
    _beams: int = field(init=False)
    _clock: SensorClock = field(init=False)

    def __post_init__(self) -> None:
        self._beams = round(360.0 / self.resolution_deg)
        self._clock = SensorClock(DEFAULT_PERIOD_S / self._beams)

    def add(self, packet: Packet, arrived: float) -> Turn | None:
        done = None
        beams = self._beams
        if packet.zero:
            if self._ranges is not None:
                done = self._finish()
            elif packet.scan_hz:
                self._clock.reset(1.0 / (packet.scan_hz * beams))
            self._ranges = array("H", bytes(2 * beams))
            self._turn += 1
        ranges = self._ranges
        if ranges is None:  # the middle of a turn whose start was not seen
            return None
        step = self.resolution_deg
        top = round(self.range_max_m * 1000.0)
        for angle, distance in zip(packet.angles_deg, packet.distances_mm, strict=True):
            if 0 < distance <= top:
                ranges[round(angle / step) % beams] = distance
        last = packet.angles_deg[-1] / 360.0 * beams
        self._clock.add(round(self._turn * beams + last), arrived)
        return done

    def _finish(self) -> Turn:
        assert self._ranges is not None
        start = self._clock.time_of(self._turn * self._beams)
        end = self._clock.time_of((self._turn + 1) * self._beams)
        return Turn(
            start=start,
            duration_s=end - start,
            angle_min=0.0,
            angle_increment=-math.radians(self.resolution_deg),  # the head turns clockwise
            ranges=self._ranges,
            range_max_m=self.range_max_m,
        )
