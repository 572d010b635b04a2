"""The agent's paced clock driven by hand: a wall clock the test moves, and an
autopilot clock already heard at a given pace."""

from __future__ import annotations

import json
from collections.abc import Iterator
from contextlib import contextmanager

import pytest

from vehicle_agents.paced_clock import PacedClock
from vehicle_agents.sensors.fcu_time import FcuClock
from vehicle_agents.streams import DEFAULT_RATES_HZ


class FakeWall:
    """A clock the test moves (monotonic or Unix seconds)."""

    def __init__(self, now: float = 100.0) -> None:
        self.now = now

    def __call__(self) -> float:
        return self.now


def fcu_at(rate: float) -> FcuClock:
    """An autopilot clock seen for 4 s of the agent's, running ``rate`` times as fast
    (rate 0: a clock that stopped counting while its messages still come)."""
    clock = FcuClock()
    for i in range(40):
        arrived = i * 0.1
        clock.add(arrived, 50.0 + rate * arrived)
    return clock


def paced_at(rate: float, wall: FakeWall | None = None) -> PacedClock:
    """A paced clock on an autopilot at ``rate``, on ``wall`` (else the real one)."""
    if wall is None:
        return PacedClock(fcu_at(rate))
    return PacedClock(fcu_at(rate), monotonic=wall)


@contextmanager
def streams_at(speedup: float) -> Iterator[None]:
    """The agents started inside ask for the position, attitude and heading streams at
    ``speedup`` times their rates: the field's rates in the simulated flight's seconds
    while the simulator paces its streams on the wall clock (remove once it streams on
    its own clock)."""
    rates = {
        name: rate * speedup
        for name, rate in DEFAULT_RATES_HZ.items()
        if name in ("GLOBAL_POSITION_INT", "ATTITUDE", "VFR_HUD")
    }
    with pytest.MonkeyPatch.context() as patch:
        patch.setenv("GCS_AGENT_STREAM_RATES_HZ", json.dumps(rates))
        yield
