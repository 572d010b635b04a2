"""The formation follower: close to the aircraft, it flies this vehicle's slot behind a
leader whose state the hub relays.

Each tick (10 Hz or more, well inside ArduCopter's GUID_TIMEOUT of 3 s and PX4's
offboard loss timeout COM_OF_LOSS_T of 1 s) it predicts the leader forward over the
link's delay at its velocity (AP_Follow's estimate), puts the slot around it, and
sends SET_POSITION_TARGET_GLOBAL_INT with the slot's position and the leader's velocity
as feed-forward. Position alone would make the autopilot chase a point that has
already moved on, trailing by speed / PSC_POSXY_P (the seed's 2.5 m); the velocity
feed-forward removes that lag.

It holds (a position target at its own stopping place, velocity zero) when:
- the leader's state is older than ``stale_s`` (1 s): flying a guess would be blind;
- another vehicle is within the minimum separation: it backs off away from it instead;
- its slot lies within the clearance of an obstacle the leader's LIDAR saw (the hub
  relays the leader's scans): it holds at the last safe point of its slot's path.

With the consensus controller (chosen per formation) the slot is not the leader's alone:
the target is the weighted mean of where the leader puts it and where each neighbour in
its communication graph puts it (`common.formation.consensus_target`), so the followers
agree on the leader and close on their slots together.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from common.formation import (
    ConsensusGains,
    Controller,
    LeaderState,
    NeighbourState,
    Offset,
    consensus_target,
    slot_target,
)
from vehicle_agents.control.formation_obstacles import ScanObstacles
from vehicle_agents.control.formation_setpoint import Action, Setpoint, position_target

if TYPE_CHECKING:
    from common.geodesy import LocalFrame


@dataclass(frozen=True)
class FollowerSettings:
    rate_hz: float = 10.0  # setpoints a second
    stale_s: float = 1.0  # a leader state older than this makes the follower hold
    max_lead_s: float = 0.5  # the most the leader is predicted forward
    back_off_ms: float = 1.0  # how fast it moves away from an intruder
    # A slot is never flown lower than this above home, whatever the leader does (a
    # leader landing, or climbing out, must not drag a follower below it into the ground).
    min_alt_m: float = 1.0
    # PX4 enters OFFBOARD only with setpoints already streaming (more than 2 Hz for a
    # while): the switch is asked for after this long of them. ArduPilot does not mind.
    prestream_s: float = 0.5


@dataclass(frozen=True)
class NeighbourReport:
    """A graph neighbour's last relayed state: position and velocity (north, east, up)
    and when (the clock the follower compares it with)."""

    position: tuple[float, float, float]
    velocity: tuple[float, float, float]
    time_s: float


class Follower:
    """One follower's slot-keeping; pure state, fed by the agent and asked each tick."""

    def __init__(
        self,
        frame: LocalFrame,
        offset: Offset,
        min_separation_m: float,
        settings: FollowerSettings | None = None,
        controller: Controller = Controller.LEADER_FOLLOWER,
        gains: ConsensusGains | None = None,
    ) -> None:
        self.frame = frame
        self.offset = offset
        self.min_separation_m = min_separation_m
        self.settings = settings or FollowerSettings()
        self.controller = controller
        self.gains = gains or ConsensusGains()
        # consensus: each graph neighbour's slot and weight, and its last relayed state
        self.graph: dict[str, tuple[Offset, float]] = {}
        self.neighbours: dict[str, NeighbourReport] = {}
        self.leader: LeaderState | None = None
        self.left_reason: str | None = None
        self._hold: tuple[float, float, float] | None = None
        # the leader's scans, and how far from what they show a slot must stay
        self.obstacles = ScanObstacles()
        self.clearance_m = 0.0  # 0: the scans are not checked
        self._last_safe: tuple[float, float, float] | None = None

    def set_offset(self, offset: Offset) -> None:
        """A new slot in flight (a shape or spacing change): the position controller,
        with its acceleration limit, glides the vehicle to it."""
        self.offset = offset

    def on_leader(self, state: LeaderState) -> None:
        if self.leader is None or state.time_s >= self.leader.time_s:
            self.leader = state

    def leave(self, reason: str) -> None:
        """Out of the formation (an RC mode change, the operator's stop)."""
        self.left_reason = reason

    def tick(
        self,
        now_s: float,
        own: tuple[float, float, float],
        others: Mapping[str, tuple[float, float, float]] = {},
    ) -> Setpoint:
        """This tick's setpoint, from the vehicle's own position (north, east, up) and
        every other vehicle's it knows of."""
        if self.left_reason is not None:
            return Setpoint(Action.LEFT, None, (0.0, 0.0, 0.0), self.left_reason)
        intruder = _nearest(own, others)
        if intruder is not None and intruder[1] < self.min_separation_m:
            name, distance, where = intruder
            away = [a - b for a, b in zip(own, where, strict=True)]
            norm = math.hypot(*away) or 1.0
            v = [self.settings.back_off_ms * a / norm for a in away]
            self._hold = None
            # The target is where it is now; the velocity carries it away.
            return Setpoint(
                Action.BACK_OFF,
                own,
                (v[0], v[1], v[2]),
                f"{name} is {distance:.1f} m away, within the {self.min_separation_m:g} m "
                "separation",
            )
        if self.leader is None or now_s - self.leader.time_s > self.settings.stale_s:
            if self._hold is None:
                self._hold = own
            age = "none yet" if self.leader is None else f"{now_s - self.leader.time_s:.1f} s old"
            return Setpoint(Action.HOLD_STALE, self._hold, (0.0, 0.0, 0.0), f"leader state {age}")
        predicted = self.leader.predicted(now_s, self.settings.max_lead_s)
        (north, east, up), (vn, ve, vu) = slot_target(predicted, self.offset)
        if up < self.settings.min_alt_m:
            up, vu = self.settings.min_alt_m, max(vu, 0.0)
        if self.controller is Controller.CONSENSUS:
            (north, east, up), _ = consensus_target(
                predicted, self.offset, self._graph_states(now_s), self.gains
            )
            up = max(up, self.settings.min_alt_m)
        blocked = self._obstacle_near(north, east)
        if blocked is not None:
            distance, (on, oe) = blocked
            # short of it: the last target that was clear, on the slot's way here
            # (checked again: the map grows), else where it is
            hold = self._last_safe
            if hold is None or self._obstacle_near(hold[0], hold[1]) is not None:
                hold = self._last_safe = own
            return Setpoint(
                Action.HOLD_OBSTACLE,
                hold,
                (0.0, 0.0, 0.0),
                f"its slot is {distance:.1f} m from an obstacle the leader saw at "
                f"{on:.1f} m north, {oe:.1f} m east, within the {self.clearance_m:g} m "
                "clearance",
            )
        crowded = _nearest((north, east, up), others)
        if crowded is not None and crowded[1] < self.min_separation_m:
            # flying into the slot would break the separation (and, once backed off,
            # would bring it straight back in): hold clear where it is instead
            if self._hold is None:
                self._hold = own
            return Setpoint(
                Action.HOLD_CLEAR,
                self._hold,
                (0.0, 0.0, 0.0),
                f"its slot is {crowded[1]:.1f} m from {crowded[0]}, within the "
                f"{self.min_separation_m:g} m separation",
            )
        self._hold = None
        self._last_safe = (north, east, up)
        return Setpoint(Action.TRACK, (north, east, up), (vn, ve, vu))

    def _obstacle_near(self, north: float, east: float) -> tuple[float, tuple[float, float]] | None:
        if self.clearance_m <= 0.0:
            return None
        return self.obstacles.nearest(north, east, self.clearance_m)

    def _graph_states(self, now_s: float) -> list[NeighbourState]:
        """The graph's neighbours with a fresh report, each predicted forward as the
        leader is; a stale one drops out of the sum (the leader's pull remains)."""
        out = []
        for vehicle_id, (offset, weight) in self.graph.items():
            report = self.neighbours.get(vehicle_id)
            if report is None or now_s - report.time_s > self.settings.stale_s:
                continue
            lead = min(max(now_s - report.time_s, 0.0), self.settings.max_lead_s)
            position = tuple(
                p + v * lead for p, v in zip(report.position, report.velocity, strict=True)
            )
            out.append(NeighbourState((position[0], position[1], position[2]), offset, weight))
        return out

    def message(
        self,
        setpoint: Setpoint,
        time_boot_ms: int,
        target_system: int,
        target_component: int,
        yaw_rad: float | None = None,
    ) -> mavlink2.MAVLink_set_position_target_global_int_message | None:
        """The SET_POSITION_TARGET_GLOBAL_INT for a setpoint (None once out of formation):
        altitude above home, velocity north-east-down."""
        return position_target(
            self.frame, setpoint, time_boot_ms, target_system, target_component, yaw_rad
        )


def _nearest(
    own: tuple[float, float, float], others: Mapping[str, tuple[float, float, float]]
) -> tuple[str, float, tuple[float, float, float]] | None:
    best: tuple[str, float, tuple[float, float, float]] | None = None
    for name, where in others.items():
        d = math.dist(own, where)
        if best is None or d < best[1]:
            best = (name, d, where)
    return best
