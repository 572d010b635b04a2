"""A formation flown in the simulator on its sped-up clock, shared by the seed-scenario
test and the benchmark.

Every vehicle is a simulated ArduCopter fed real MAVLink bytes (each setpoint is packed
and parsed again before the simulator's message handler takes it). The leader is a
vehicle flying the route with position, velocity and yaw targets; its state reaches the
followers after a link delay, and each follower runs the agent's `Follower` at 10 Hz.
The tracking error is each follower's distance from its slot around the leader's true
state, horizontal, sampled at every tick while the route is on a leg.
"""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from backend.formation.route import LeaderRoute
from common.formation import (
    ConsensusGains,
    Controller,
    LeaderState,
    Offset,
    Shape,
    shape_offsets,
    slot_target,
)
from common.geodesy import GeoPoint, LocalFrame
from simulator import DEFAULT_HOME, Copter
from simulator.mavconst import CopterMode
from simulator.mavlink.commands import MessageHandler
from simulator.mavlink.streams import StreamSchedule
from simulator.mavlink.telemetry import DEFAULT_RATES_HZ, TelemetryBuilder
from vehicle_agents.control.formation_follower import Follower, FollowerSettings, NeighbourReport
from vehicle_agents.control.formation_setpoint import Action, Setpoint, position_target

TICK_S = 0.1  # the follower's 10 Hz
GCS_SYSID, GCS_COMPID = 255, 190


class SimVehicle:
    """One simulated copter, its MAVLink handler, and a GCS-side packer."""

    def __init__(self, home: GeoPoint, system_id: int) -> None:
        self.system_id = system_id
        self.copter = Copter(home, system_id=system_id)
        self.handler = MessageHandler(
            self.copter, TelemetryBuilder(self.copter, boot_epoch_s=1.7e9), system_id
        )
        self.streams = StreamSchedule(DEFAULT_RATES_HZ, now=0.0)
        self._gcs = mavlink2.MAVLink(None, srcSystem=GCS_SYSID, srcComponent=GCS_COMPID)
        self._parser = mavlink2.MAVLink(None)
        self.bytes_sent = 0

    def send(self, message: mavlink2.MAVLink_message) -> None:
        frame = message.pack(self._gcs)
        self.bytes_sent += len(frame)
        [decoded] = self._parser.parse_buffer(frame)
        self.handler.handle(decoded, self.streams, now=self.copter.time_s)

    def local(self, frame: LocalFrame) -> tuple[float, float, float]:
        """(north, east, up above home) in the formation's frame."""
        p = self.copter.position()
        east, north = frame.to_local(p.lat, p.lon)
        return north, east, self.copter.relative_alt

    def state(self, frame: LocalFrame, time_s: float) -> LeaderState:
        north, east, up = self.local(frame)
        b = self.copter.body
        return LeaderState(north, east, up, b.vn, b.ve, -b.vd, b.yaw, time_s)

    def report(self, frame: LocalFrame, time_s: float) -> NeighbourReport:
        """Its state as the hub relays it to a consensus neighbour."""
        s = self.state(frame, time_s)
        return NeighbourReport((s.north, s.east, s.up), (s.vn, s.ve, s.vu), time_s)


@dataclass
class FormationRun:
    errors_xy: dict[int, list[float]] = field(default_factory=dict)  # per follower, in legs
    errors_z: dict[int, list[float]] = field(default_factory=dict)
    min_separation_m: float = math.inf
    actions: dict[int, list[Action]] = field(default_factory=dict)
    action_times: list[float] = field(default_factory=list)  # the route's clock, per tick

    def rms_xy(self, follower: int) -> float:
        e = self.errors_xy[follower]
        return math.sqrt(sum(x * x for x in e) / len(e))

    def max_xy(self, follower: int) -> float:
        return max(self.errors_xy[follower])

    @property
    def worst_rms_xy(self) -> float:
        return max(self.rms_xy(f) for f in self.errors_xy)


def square_route(side_m: float, alt_m: float) -> list[tuple[float, float, float]]:
    """The seed's square: north, then east, then back, ending where it began."""
    return [
        (0.0, 0.0, alt_m),
        (side_m, 0.0, alt_m),
        (side_m, side_m, alt_m),
        (0.0, side_m, alt_m),
        (0.0, 0.0, alt_m),
    ]


def take_off(vehicle: SimVehicle, altitude: float) -> None:
    copter = vehicle.copter
    copter.advance(12.0)  # the EKF takes the GPS after a steady fix
    assert copter.set_mode(CopterMode.GUIDED).name == "ACCEPTED"
    assert copter.arm().name == "ACCEPTED"
    assert copter.takeoff(altitude).name == "ACCEPTED"


def fly_formation(
    *,
    speed_ms: float = 1.5,
    side_m: float = 20.0,
    pause_s: float = 2.0,
    leader_alt_m: float = 8.0,
    follower_alts_m: Sequence[float] = (2.0, 3.0),
    shape: Shape = Shape.TRIANGLE,
    spacing_m: float = 3.0,
    link_delay_s: float = 0.0,
    min_separation_m: float = 1.5,
    feed_forward: bool = True,
    settings: FollowerSettings | None = None,
    controller: Controller = Controller.LEADER_FOLLOWER,
    gains: ConsensusGains | None = None,
    on_tick: Callable[[float, list[SimVehicle], list[Follower]], None] | None = None,
    leader_cut_at_s: float | None = None,
    route_laps: float = 1.0,
) -> FormationRun:
    """Take off, settle in the slots, fly the square once, and measure the tracking.
    A consensus follower hears every other follower (weight 1), their states relayed
    with the leader's, after the same delay."""
    frame = LocalFrame(DEFAULT_HOME.lat, DEFAULT_HOME.lon, DEFAULT_HOME.alt)
    ups = [a - leader_alt_m for a in follower_alts_m]
    offsets = shape_offsets(shape, len(follower_alts_m), spacing_m, ups)
    leader = SimVehicle(DEFAULT_HOME, 1)
    followers: list[SimVehicle] = []
    controllers: list[Follower] = []
    for i, offset in enumerate(offsets):
        # each starts on the ground under its slot (heading north at the first leg)
        dn, de, _ = offset.north_east_up(0.0)
        lat, lon = frame.to_geo(de, dn)
        followers.append(SimVehicle(GeoPoint(lat, lon, DEFAULT_HOME.alt), i + 2))
        controllers.append(Follower(frame, offset, min_separation_m, settings, controller, gains))
    for i, c in enumerate(controllers):
        c.graph = {str(j + 2): (o, 1.0) for j, o in enumerate(offsets) if j != i}
    everyone = [leader, *followers]
    take_off(leader, leader_alt_m)
    for vehicle, alt in zip(followers, follower_alts_m, strict=True):
        take_off(vehicle, alt)

    route = LeaderRoute(square_route(side_m, leader_alt_m), speed_ms, pause_s)
    settle_s = 25.0  # climb and settle before the route's clock starts
    run = FormationRun(
        {v.system_id: [] for v in followers},
        {v.system_id: [] for v in followers},
        actions={v.system_id: [] for v in followers},
    )
    # leader states (and the followers' own, for consensus) on their way to the followers
    in_flight: deque[tuple[LeaderState, dict[str, NeighbourReport]]] = deque()
    t = 0.0
    end = settle_s + route.duration_s * route_laps + 2.0
    while t < end:
        route_t = t - settle_s
        # the leader flies its route: position, velocity feed-forward and the leg's heading
        want = route.state_at(max(route_t, 0.0))
        leader_sp = Setpoint(
            Action.TRACK, (want.north, want.east, want.up), (want.vn, want.ve, want.vu)
        )
        # the formation starts once every member has climbed (the plan needs them ready)
        started = t >= settle_s - 10.0
        if started:
            msg = position_target(frame, leader_sp, int(t * 1000), 1, 1, want.heading_rad)
            assert msg is not None
            leader.send(msg)
        # its state, stamped now, arrives after the link's delay (until the link is cut)
        if leader_cut_at_s is None or route_t < leader_cut_at_s:
            reports = {str(v.system_id): v.report(frame, t) for v in followers}
            in_flight.append((leader.state(frame, t), reports))
        while in_flight and in_flight[0][0].time_s <= t - link_delay_s + 1e-9:
            state, reports = in_flight.popleft()
            for c in controllers:
                c.on_leader(state)
                c.neighbours = reports
        positions = {v.system_id: v.local(frame) for v in everyone}
        if started:
            run.action_times.append(route_t)
        for vehicle, controller in zip(followers, controllers, strict=True):
            if not started:
                break
            others = {str(k): p for k, p in positions.items() if k != vehicle.system_id}
            sp = controller.tick(t, positions[vehicle.system_id], others)
            run.actions[vehicle.system_id].append(sp.action)
            if not feed_forward and sp.action is Action.TRACK:
                sp = Setpoint(sp.action, sp.position, (0.0, 0.0, 0.0))
            msg = controller.message(sp, int(t * 1000), vehicle.system_id, 1)
            if msg is not None:
                vehicle.send(msg)
        if on_tick is not None:
            on_tick(t, everyone, controllers)
        t += TICK_S
        for vehicle in everyone:
            vehicle.copter.advance(TICK_S)
        # measure on the vehicles' true state after the step
        positions = {v.system_id: v.local(frame) for v in everyone}
        pts = list(positions.values())
        for i in range(len(pts)):
            for j in range(i + 1, len(pts)):
                run.min_separation_m = min(run.min_separation_m, math.dist(pts[i], pts[j]))
        route_t = t - settle_s
        if route_t >= 0 and route.leg_at(route_t) is not None:
            truth = leader.state(frame, t)
            for vehicle, controller in zip(followers, controllers, strict=True):
                slot, _ = slot_target(truth, controller.offset)
                here = positions[vehicle.system_id]
                run.errors_xy[vehicle.system_id].append(math.dist(slot[:2], here[:2]))
                run.errors_z[vehicle.system_id].append(abs(slot[2] - here[2]))
    return run


def offsets_of(controllers: Sequence[Follower]) -> list[Offset]:
    return [c.offset for c in controllers]
