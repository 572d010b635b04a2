"""The agent's side of a formation: the hub's slots, leader states and scans in, a
setpoint to the flight controller every tick of the agent's paced clock
(`vehicle_agents/sensors/paced_clock.py`), events out.

ArduPilot flies the setpoints in GUIDED. PX4 takes them only in OFFBOARD, and only once
setpoints are already streaming: the agent starts the stream before it asks for the
switch, and if the stream stops PX4 falls back to its COM_OBL_RC_ACT action on its own.
A mode change it did not make (the RC transmitter's switch) takes it out of the
formation at once: it stops sending, so the pilot's mode rules.
"""

from __future__ import annotations

import logging
import math
import time
from collections.abc import Callable
from typing import TYPE_CHECKING

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from common.formation import ConsensusGains, Controller, LeaderState, Offset, OffsetFrame

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
from vehicle_agents.control.formation_follower import Follower, FollowerSettings, NeighbourReport
from vehicle_agents.control.formation_modes import ModeWatch
from vehicle_agents.control.formation_setpoint import Action
from vehicle_agents.fcu.link import FcuLink
from vehicle_agents.fcu.messages import MavMessage
from vehicle_agents.fcu.modes import mode_name
from vehicle_agents.sensors.paced_clock import PacedClock

log = logging.getLogger(__name__)

EmitEvent = Callable[[EventKind, str, int | None], None]
FormationMessage = FormationSlot | FormationEnd | LeaderUpdate | LeaderScan


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
