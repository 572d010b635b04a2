"""The agent's paced clock driven by hand: a wall clock the test moves, and an
autopilot clock already heard at a given pace."""

from __future__ import annotations

from vehicle_agents.sensors.fcu_time import FcuClock
from vehicle_agents.sensors.paced_clock import PacedClock


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
