"""The formation follower: close to the aircraft, it flies this vehicle's slot behind a
leader whose state the hub relays.

Each tick (10 Hz or more, well inside ArduCopter's GUID_TIMEOUT of 3 s and PX4's
offboard loss timeout COM_OF_LOSS_T of 1 s) it predicts the leader forward over the
link's delay at its velocity (AP_Follow's estimate), puts the slot around it, and
sends SET_POSITION_TARGET_GLOBAL_INT with the slot's position and the leader's velocity
as feed-forward. Position alone would make the autopilot chase a point that has
already moved on, trailing by speed / PSC_POSXY_P (the seed's 2.5 m); the velocity
feed-forward removes that lag.

ArduPilot flies these in GUIDED. PX4 takes them only in OFFBOARD, and only once
setpoints are already streaming: the agent starts the stream before it asks for the
switch, and if the stream stops PX4 falls back to its COM_OBL_RC_ACT action on its own.

It holds (a position target at its own stopping place, velocity zero) when:
- the leader's state is older than ``stale_s`` (1 s): flying a guess would be blind;
- another vehicle is within the minimum separation: it backs off away from it instead;
- its slot lies within the clearance of an obstacle the leader's LIDAR saw (the hub
  relays the leader's scans): it holds at the last safe point of its slot's path.

With the consensus controller (chosen per formation) the slot is not the leader's alone:
the target is the weighted mean of where the leader puts it and where each neighbour in
its communication graph puts it (`common.formation.consensus_target`), so the followers
agree on the leader and close on their slots together.
A mode change it did not make (the RC transmitter's switch) takes it out of the
formation at once: it stops sending, so the pilot's mode rules.
"""

from __future__ import annotations

import logging
import math
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from enum import StrEnum
from typing import TYPE_CHECKING

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from common.formation import (
    ConsensusGains,
    Controller,
    LeaderState,
    NeighbourState,
    Offset,
    OffsetFrame,
    consensus_target,
    slot_target,
)

if TYPE_CHECKING:
    from common.geodesy import LocalFrame
from protocol.messages import (
    EventKind,
    FormationEnd,
    FormationSlot,
    HoldCommand,
    LeaderScan,
    LeaderUpdate,
)
from vehicle_agents.control.executor import CommandExecutor
from vehicle_agents.control.formation_obstacles import ScanObstacles
from vehicle_agents.fcu.link import FcuLink
from vehicle_agents.fcu.messages import MavMessage
from vehicle_agents.fcu.modes import mode_name
from vehicle_agents.sensors.paced_clock import PacedClock

log = logging.getLogger(__name__)

EmitEvent = Callable[[EventKind, str, int | None], None]
FormationMessage = FormationSlot | FormationEnd | LeaderUpdate | LeaderScan

# Position and velocity used; acceleration, yaw and yaw rate ignored. ArduCopter reads
# any set bit of a group as "ignore the group", PX4 each axis: both fly this the same.
POSVEL_TYPE_MASK = (
    mavlink2.POSITION_TARGET_TYPEMASK_AX_IGNORE
    | mavlink2.POSITION_TARGET_TYPEMASK_AY_IGNORE
    | mavlink2.POSITION_TARGET_TYPEMASK_AZ_IGNORE
    | mavlink2.POSITION_TARGET_TYPEMASK_YAW_IGNORE
    | mavlink2.POSITION_TARGET_TYPEMASK_YAW_RATE_IGNORE
)
# The same with a yaw: a leader flown by the agent faces along its route.
POSVEL_YAW_TYPE_MASK = POSVEL_TYPE_MASK & ~mavlink2.POSITION_TARGET_TYPEMASK_YAW_IGNORE


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


class Action(StrEnum):
    TRACK = "track"
    HOLD_STALE = "hold_stale"
    BACK_OFF = "back_off"
    HOLD_CLEAR = "hold_clear"  # its slot is within the separation of another vehicle
    HOLD_OBSTACLE = "hold_obstacle"  # its slot is within the clearance of a scanned obstacle
    LEFT = "left"  # out of the formation: sends nothing


@dataclass(frozen=True)
class Setpoint:
    """What to send this tick: a local position (north, east, up) and velocity."""

    action: Action
    position: tuple[float, float, float] | None
    velocity: tuple[float, float, float]
    reason: str = ""


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


def position_target(
    frame: LocalFrame,
    setpoint: Setpoint,
    time_boot_ms: int,
    target_system: int,
    target_component: int,
    yaw_rad: float | None = None,
) -> mavlink2.MAVLink_set_position_target_global_int_message | None:
    if setpoint.position is None:
        return None
    north, east, up = setpoint.position
    lat, lon = frame.to_geo(east, north)
    vn, ve, vu = setpoint.velocity
    return mavlink2.MAVLink_set_position_target_global_int_message(
        time_boot_ms & 0xFFFFFFFF,
        target_system,
        target_component,
        mavlink2.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT,
        POSVEL_TYPE_MASK if yaw_rad is None else POSVEL_YAW_TYPE_MASK,
        round(lat * 1e7),
        round(lon * 1e7),
        up,
        vn,
        ve,
        -vu,
        0.0,
        0.0,
        0.0,
        0.0 if yaw_rad is None else yaw_rad,
        0.0,
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


class ModeWatch:
    """Whose mode the vehicle is in during a formation: the agent's, or a pilot's.

    The agent may change only one thing, the mode it found at the join to the guided
    mode. Any other change (away from guided once in it, or from the join's mode to
    anything but guided before the agent's switch) is the RC pilot's or another GCS's,
    and takes the vehicle out. A second formation on the same vehicles shows why both
    halves matter: the followers are already in their slots, so the operator can act
    within the pre-stream's half second, before the agent has asked for guided and
    before a guided heartbeat has come; the agent must not then switch the pilot's
    LOITER back to GUIDED."""

    def __init__(self, guided: str | None, join_mode: str | None) -> None:
        self.guided = guided
        self.join_mode = join_mode
        self.seen_guided = join_mode is not None and join_mode == guided

    def observe(self, mode: str | None) -> str | None:
        """The reason to leave, if ``mode`` (a heartbeat's) is someone else's doing."""
        if mode is None:
            return None
        if mode == self.guided:
            self.seen_guided = True
            return None
        if self.join_mode is None:
            self.join_mode = mode  # the first heartbeat since the join
            return None
        if self.seen_guided or mode != self.join_mode:
            return f"the vehicle changed to {mode} (RC or another GCS): out of the formation"
        return None

    def needs_switch(self, mode: str | None) -> bool:
        """Whether the agent should ask for guided: the vehicle is still in the mode it
        was in at the join (a pilot's change would have taken it out already)."""
        return mode != self.guided and not self.seen_guided


class FormationRunner:
    """The agent's side of a formation: slots and leader states from the hub in, a
    setpoint to the flight controller every tick, events out when it holds, backs off,
    or leaves because someone else changed the mode (the RC pilot outranks it)."""

    def __init__(
        self,
        link: FcuLink,
        executor: CommandExecutor,
        emit: EmitEvent,
        settings: FollowerSettings | None = None,
        clock: PacedClock | None = None,
        wall: Callable[[], float] = time.time,
    ) -> None:
        self._link = link
        self._executor = executor
        self._emit = emit
        self.settings = settings or FollowerSettings()
        # The follower's clock is the agent's paced one (the autopilot's seconds, never
        # slower than the wall's): its ticks, its pre-stream and the ages of what the hub
        # relays. The relayed stamps are Unix time (each member's agent stamps its
        # telemetry, the hub a virtual leader's state): comparable across the fleet on
        # synchronised clocks, and the only stamps every member and the hub share. See
        # `_stamped` for how a stamp's age is carried onto the paced clock.
        self._clock = clock or PacedClock()
        self._wall = wall
        self._leader_stamp = -math.inf  # the newest leader stamp taken (Unix)
        self.formation_id: str | None = None
        self.follower: Follower | None = None
        self._neighbours: dict[str, tuple[float, float, float]] = {}
        self._started_at = 0.0
        self._mode_asked = False
        self._modes = ModeWatch(None, None)
        self._last_action: Action | None = None
        self._ending: FormationEnd | None = None
        self._face_heading = False
        self.sent = 0
        link.listeners.append(self._on_message)

    def on_hub(self, message: FormationMessage) -> None:
        match message:
            case FormationSlot():
                self._on_slot(message)
            case LeaderUpdate() if message.formation_id == self.formation_id:
                assert self.follower is not None
                if message.time < self._leader_stamp:
                    return  # overtaken on the way (newest wins, by the sender's stamp)
                self._leader_stamp = message.time
                self.follower.on_leader(
                    LeaderState(
                        message.north,
                        message.east,
                        message.up,
                        message.vn,
                        message.ve,
                        message.vu,
                        math.radians(message.heading_deg),
                        self._stamped(message.time),
                    )
                )
                self._neighbours = {
                    n.vehicle_id: (n.north, n.east, n.up) for n in message.neighbours
                }
                self.follower.neighbours = {
                    n.vehicle_id: NeighbourReport(
                        (n.north, n.east, n.up),
                        (n.vn, n.ve, n.vu),
                        self._stamped(n.time or message.time),
                    )
                    for n in message.neighbours
                }
            case LeaderScan() if message.formation_id == self.formation_id:
                assert self.follower is not None
                self.follower.obstacles.add(message.north, message.east, message.seq)
            case FormationEnd() if message.formation_id == self.formation_id:
                self._ending = message

    def _on_slot(self, slot: FormationSlot) -> None:
        offset = Offset(slot.x, slot.y, slot.up, OffsetFrame(slot.frame))
        if self.follower is not None and slot.formation_id == self.formation_id:
            self.follower.set_offset(offset)
            self.follower.min_separation_m = slot.min_separation_m
            self.follower.graph = _graph(slot)
            self.follower.clearance_m = slot.obstacle_clearance_m
            self._emit("formation", f"new slot in {slot.formation_id}: {_describe(offset)}", 6)
            return
        self.formation_id = slot.formation_id
        # pymap3d brings numpy: imported when a formation starts, not at the agent's start
        # (a Pi Zero's start-up and memory budget, tests/unit/test_onboard_footprint.py)
        from common.geodesy import LocalFrame

        frame = LocalFrame(slot.origin_lat, slot.origin_lon)
        self.follower = Follower(
            frame,
            offset,
            slot.min_separation_m,
            self.settings,
            Controller(slot.controller),
            ConsensusGains(slot.k_leader, slot.k_neighbour),
        )
        self.follower.graph = _graph(slot)
        self.follower.clearance_m = slot.obstacle_clearance_m
        self._face_heading = slot.face_heading
        self._started_at = self._clock()
        self._leader_stamp = -math.inf
        self._mode_asked = False
        heartbeat = self._link.latest.get("HEARTBEAT")
        self._modes = ModeWatch(
            self._guided_mode(), mode_name(heartbeat) if heartbeat is not None else None
        )
        self._last_action = None
        self._neighbours = {}
        how = "" if slot.controller == "leader_follower" else f" ({slot.controller})"
        self._emit("formation", f"joined {slot.formation_id}{how}: {_describe(offset)}", 6)

    def _on_message(self, message: MavMessage) -> None:
        """The RC pilot's (or another GCS's) mode change takes the vehicle out."""
        if self.follower is None or self.follower.left_reason is not None:
            return
        if message.get_type() != "HEARTBEAT" or message.get_srcSystem() != self._link.target_system:
            return
        reason = self._modes.observe(mode_name(message))
        if reason is not None:
            self.follower.leave(reason)
            self._emit("formation", f"left {self.formation_id}: {reason}", 4)

    def _guided_mode(self) -> str | None:
        return self._link.modes.guided_mode if self._link.modes is not None else None

    def _own_position(self, frame: LocalFrame) -> tuple[float, float, float] | None:
        position = self._link.latest.get("GLOBAL_POSITION_INT")
        if position is None:
            return None
        east, north = frame.to_local(position.lat / 1e7, position.lon / 1e7)
        return north, east, position.relative_alt / 1000.0

    async def tick(self) -> None:
        follower = self.follower
        if self._ending is not None:
            ending, self._ending = self._ending, None
            # an end that was overtaken by the next formation's slot ends nothing
            if ending.formation_id == self.formation_id:
                await self._end(ending)
                return
        if follower is None or follower.left_reason is not None or self._link.target_system is None:
            return
        own = self._own_position(follower.frame)
        if own is None:
            return
        now = self._clock()
        setpoint = follower.tick(now, own, self._neighbours)
        if setpoint.action is not self._last_action:
            self._last_action = setpoint.action
            if setpoint.action in (
                Action.HOLD_STALE,
                Action.BACK_OFF,
                Action.HOLD_CLEAR,
                Action.HOLD_OBSTACLE,
            ):
                self._emit("formation", f"{setpoint.action.value}: {setpoint.reason}", 4)
            elif setpoint.action is Action.TRACK:
                self._emit("formation", "tracking its slot", 6)
        boot_ms = int((now - self._started_at) * 1000)
        yaw = None
        if self._face_heading and setpoint.action is Action.TRACK and follower.leader:
            yaw = follower.leader.heading_rad
        message = follower.message(
            setpoint, boot_ms, self._link.target_system, self._link.target_component, yaw
        )
        if message is None:
            return
        try:
            self._link.send(message)
            self.sent += 1
        except ConnectionError:
            return  # the flight controller link is down; the link says so itself
        if not self._mode_asked and now - self._started_at >= self.settings.prestream_s:
            self._mode_asked = True
            heartbeat = self._link.latest.get("HEARTBEAT")
            if self._modes.needs_switch(mode_name(heartbeat) if heartbeat else None):
                self._enter_guided()

    def _enter_guided(self) -> None:
        modes = self._link.modes
        guided = self._guided_mode()
        if modes is None or guided is None:
            return
        setting = modes.settings[guided]
        self._link.send_command_long(
            mavlink2.MAV_CMD_DO_SET_MODE,
            0,
            [setting.base_mode, setting.custom_mode, setting.custom_sub_mode],
        )

    async def _end(self, ending: FormationEnd) -> None:
        follower, self.follower = self.follower, None
        self.formation_id = None
        if follower is None:
            return
        self._emit("formation", f"left {ending.formation_id}: {ending.reason or 'ended'}", 5)
        if follower.left_reason is None:
            # stop here: PX4 would otherwise run its offboard-loss action when the
            # setpoints stop, ArduPilot drift on its last target until GUID_TIMEOUT
            outcome = await self._executor.execute(HoldCommand())
            if outcome.status != "accepted":
                self._emit("formation", f"hold at the end refused: {outcome.message}", 2)

    async def run(self) -> None:
        period = 1.0 / self.settings.rate_hz  # setpoints a second of the autopilot's
        while True:
            await self.tick()
            await self._clock.sleep(period)

    def _stamped(self, unix_s: float) -> float:
        """A relayed Unix stamp as an instant of the follower's paced clock: its age on
        arrival (the wall's, times the autopilot's pace) before now. From there it ages
        on the paced clock, so every age the follower reckons is at least the wall's
        (a stalled autopilot clock never keeps a stale leader fresh) and, when the fleet's
        simulators share one speed-up, the age in the leader's seconds, which is what its
        velocity is predicted over. A stamp ahead of this agent's wall clock (clocks
        out of step) counts as just sent, never as a future one."""
        age_s = max(0.0, self._wall() - unix_s) * self._clock.pace
        return self._clock() - age_s


def _describe(offset: Offset) -> str:
    axes = "forward/right" if offset.frame is OffsetFrame.HEADING else "north/east"
    return f"{offset.x:.1f} m, {offset.y:.1f} m ({axes}), {offset.up:+.1f} m up"


def _graph(slot: FormationSlot) -> dict[str, tuple[Offset, float]]:
    return {
        e.vehicle_id: (Offset(e.x, e.y, e.up, OffsetFrame(e.frame)), e.weight) for e in slot.graph
    }
