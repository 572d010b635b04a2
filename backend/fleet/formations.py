"""Formations in flight: the hub hands each member its slot and relays the leader's state.

The followers' control runs in their agents (vehicle_agents/formation.py), close to the
aircraft; the hub only moves data. At ``rate_hz`` it sends every follower the newest
leader state (newest wins, nothing queues behind a slow link) with the other members'
positions for the separation check.

A virtual leader is the route's clock on the hub. A vehicle leader is itself a member:
its agent follows the virtual route at a zero offset, facing along it, and the followers
take the leader vehicle's reported state, so they keep station on where it really is.
"""

from __future__ import annotations

import asyncio
import json
import logging
import math
import secrets
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

from pydantic import ValidationError
from sqlalchemy.exc import SQLAlchemyError
from starlette.websockets import WebSocketDisconnect

from backend.errors import Conflict, NotFound
from backend.fleet.airborne import not_airborne
from backend.fleet.formation_metrics import TrackingMetrics, tracking_summary
from backend.fleet.registry import FleetRegistry
from backend.fleet.safety_gate import SafetyGate, snapshot_of
from backend.missions.formation import FormationPlan, plan_formation
from backend.missions.formation.planner import check_separation, follower_offsets
from backend.missions.formation.schemas import FormationRequest, ShapeChange
from backend.storage.formations import FormationRepository, StoredFormation
from common.formation import LeaderState, Offset, slot_target
from common.geodesy import LocalFrame
from protocol.messages import (
    FormationEnd,
    FormationSlot,
    GraphEdge,
    LeaderScan,
    LeaderUpdate,
    Message,
    Neighbour,
)

log = logging.getLogger(__name__)

# A leader sample older than this is not relayed: the followers' own 1 s rule then holds
# them, rather than a relayed state that looks fresh.
MAX_RELAY_AGE_S = 1.0
# The route's clock starts once every follower is this close to its slot (horizontally
# and vertically): a leg flown while followers are still joining measures nothing.
FORM_UP_M = 0.5
# A formation whose followers have not all reached their slots this long after it started
# ends (its members hold) with the reason, rather than sit "joining" for ever.
JOIN_TIMEOUT_S = 60.0
# The leader's scans go to the followers at most this often (the newest, never a queue):
# an obstacle moves with the scene, not the sensor's 10 Hz, and each scan is kilobytes.
SCAN_RELAY_HZ = 2.0


@dataclass(frozen=True)
class ScanPoints:
    """A vehicle's newest scan as a formation's followers get it: its time, its number,
    and its returns' north and east metres on the formation's plane."""

    time: float
    seq: int
    north: Sequence[float]
    east: Sequence[float]


# (vehicle id, the formation's frame, the scan number already relayed) -> its newest
# scan if newer; given by the hub's wiring (the scans sit above the fleet).
ScanSource = Callable[[str, LocalFrame, int | None], ScanPoints | None]


@dataclass
class ActiveFormation:
    id: str
    request: FormationRequest
    plan: FormationPlan
    started_at: float
    started_by: str = ""
    stopped: str | None = None  # why, once stopped
    stopped_by: str | None = None
    stopped_at: float | None = None
    formed_at: float | None = None  # when every follower reached its slot: the route starts
    offsets: dict[str, Offset] = field(default_factory=dict)
    metrics: TrackingMetrics = field(default_factory=TrackingMetrics)
    scan_seq: int | None = None  # the leader's scan last relayed
    scan_relayed_at: float = 0.0

    @property
    def followers(self) -> list[str]:
        return list(self.offsets)

    @property
    def members(self) -> list[str]:
        leader = [self.plan.leader_id] if self.plan.leader_id else []
        return leader + self.followers


class FormationService:
    def __init__(
        self,
        registry: FleetRegistry,
        safety: SafetyGate,
        rate_hz: float = 10.0,
        clock: Callable[[], float] = time.time,
        repository: FormationRepository | None = None,
        join_timeout_s: float = JOIN_TIMEOUT_S,
        speedup: float = 1.0,
    ) -> None:
        self._registry = registry
        # A simulated fleet's speed-up (its seconds per wall second, one for the whole
        # fleet; 1 for aircraft): the route, the relay's rate and the ages the hub
        # reckons run in the vehicles' seconds, as their agents' followers do. The stamps
        # stay Unix time, the one clock every member shares.
        self._speedup = speedup
        self._join_timeout_s = join_timeout_s
        self._safety = safety
        self._repository = repository
        self._period = 1.0 / (rate_hz * speedup)
        self._clock = clock
        self._formations: dict[str, ActiveFormation] = {}
        self.scan_source: ScanSource | None = None

    def busy(self) -> set[str]:
        return {v for f in self.active() for v in f.members}

    def active(self) -> list[ActiveFormation]:
        return [f for f in self._formations.values() if f.stopped is None]

    def get(self, formation_id: str) -> ActiveFormation:
        formation = self._formations.get(formation_id)
        if formation is None:
            raise NotFound(f"no formation {formation_id!r}")
        return formation

    async def start(
        self, request: FormationRequest, max_speed_ms: float = 5.0, by: str = ""
    ) -> ActiveFormation:
        """Check the request (FormationRefused names the reason), then send each member
        its slot. The followers hold until the first leader state reaches them."""
        members = [f.vehicle_id for f in request.followers]
        if request.leader_id:
            members.append(request.leader_id)
        vehicles, not_ready, grounded = {}, {}, {}
        for vehicle_id in members:
            record = self._registry.get(vehicle_id)  # VehicleNotFound for an unknown id
            if record.channel is None:
                raise Conflict(f"{vehicle_id} is not connected")
            vehicles[vehicle_id] = snapshot_of(record)
            state = record.state
            if state is not None and state.ready_to_fly is False:
                not_ready[vehicle_id] = state.not_ready_reason or "not ready"
            if (why := not_airborne(vehicle_id, state)) is not None:
                grounded[vehicle_id] = why
        rails = self._safety.site_rails()
        plan = plan_formation(
            request,
            rails=rails,
            vehicles=vehicles,
            not_ready=not_ready,
            not_airborne=grounded,
            busy=self.busy(),
            max_speed_ms=max_speed_ms,
        )
        # unique across the hub's restarts too: the id is the stored row's key
        formation = ActiveFormation(
            f"formation-{secrets.token_hex(4)}",
            request,
            plan,
            self._clock(),
            started_by=by,
            offsets=plan.offsets,
        )
        self._formations[formation.id] = formation
        await self._send_slots(formation)
        await self._store(formation)
        return formation

    async def change_shape(self, formation_id: str, change: ShapeChange) -> ActiveFormation:
        """New slots in flight; the followers' position controllers glide to them."""
        formation = self.get(formation_id)
        if formation.stopped is not None:
            raise Conflict(f"{formation_id} has stopped")
        offsets = follower_offsets(formation.request, change.shape, change.spacing_m)
        check_separation(offsets, formation.plan.min_separation_m)
        formation.offsets = offsets
        formation.request = formation.request.model_copy(
            update={k: v for k, v in change.model_dump().items() if v is not None}
        )
        await self._send_slots(formation)
        await self._store(formation)
        return formation

    async def stop(
        self, formation_id: str, reason: str = "stopped by the operator", by: str | None = None
    ) -> None:
        formation = self.get(formation_id)
        if formation.stopped is not None:
            return
        formation.stopped, formation.stopped_by = reason, by
        formation.stopped_at = self._clock()
        for vehicle_id in formation.members:
            await self._send(vehicle_id, FormationEnd(formation_id=formation.id, reason=reason))
        await self._store(formation)

    async def _store(self, formation: ActiveFormation) -> None:
        """The formation's row: its request, who started and stopped it, and (once
        stopped) its tracking figures. A store that fails is logged; the flight goes on."""
        if self._repository is None:
            return
        stopped = formation.stopped_at is not None
        row = StoredFormation(
            id=formation.id,
            started=formation.started_at,
            started_by=formation.started_by,
            leader_id=formation.plan.leader_id,
            request_json=formation.request.model_dump_json(),
            stopped=formation.stopped_at,
            stopped_by=formation.stopped_by,
            stop_reason=formation.stopped,
            tracking_json=json.dumps(tracking_summary(formation.metrics)) if stopped else None,
        )
        try:
            await asyncio.to_thread(self._repository.save, row)
        except SQLAlchemyError as error:
            log.warning("formation %s not stored: %s", formation.id, error)

    async def close_left_open(self) -> None:
        """At the hub's start: formations the last run left flying are over (the followers'
        agents held them once the leader's relay stopped); say so in the store and the
        hub's log, rather than list them as running for ever."""
        if self._repository is None:
            return
        reason = "stopped: the hub restarted while it flew"
        try:
            closed = await asyncio.to_thread(
                self._repository.close_left_open, self._clock(), reason
            )
        except SQLAlchemyError as error:
            log.error("could not close the formations left open: %s", error)
            return
        for formation_id in closed:
            log.warning("formation %s %s", formation_id, reason)

    def stored(self, limit: int) -> list[StoredFormation]:
        return [] if self._repository is None else self._repository.recent(limit)

    async def _send_slots(self, formation: ActiveFormation) -> None:
        origin = formation.plan.frame.origin
        slots = dict(formation.offsets)
        if formation.plan.leader_id:
            slots[formation.plan.leader_id] = Offset(0.0, 0.0, 0.0)
        plan = formation.plan
        for vehicle_id, offset in slots.items():
            graph = [
                GraphEdge(
                    vehicle_id=heard,
                    x=slots[heard].x,
                    y=slots[heard].y,
                    up=slots[heard].up,
                    frame=slots[heard].frame.value,
                    weight=weight,
                )
                for heard, weight in plan.graph.get(vehicle_id, {}).items()
            ]
            await self._send(
                vehicle_id,
                FormationSlot(
                    formation_id=formation.id,
                    origin_lat=origin.lat,
                    origin_lon=origin.lon,
                    x=offset.x,
                    y=offset.y,
                    up=offset.up,
                    frame=offset.frame.value,
                    min_separation_m=formation.plan.min_separation_m,
                    obstacle_clearance_m=formation.request.obstacle_clearance_m,
                    face_heading=vehicle_id == formation.plan.leader_id,
                    controller=plan.controller.value,
                    k_leader=plan.gains.k_leader,
                    k_neighbour=plan.gains.k_neighbour,
                    graph=graph,
                ),
            )

    async def _send(self, vehicle_id: str, message: Message) -> None:
        channel = self._registry.get(vehicle_id).channel
        if channel is None:
            return  # offline: its agent holds on the stale leader state
        try:
            await channel.send_frame(message)
        except (RuntimeError, OSError, WebSocketDisconnect) as error:
            log.info("formation message to %s not sent: %s", vehicle_id, error)

    # -- the relay -------------------------------------------------------------

    def _local(self, formation: ActiveFormation, vehicle_id: str) -> Neighbour | None:
        """A member's last report in the formation's frame, with its velocity and time
        (a consensus follower predicts its neighbours forward over the delay)."""
        record = self._registry.get(vehicle_id)
        state = record.state
        if state is None or state.lat is None or state.lon is None or state.alt_rel is None:
            return None
        east, north = formation.plan.frame.to_local(state.lat, state.lon)
        return Neighbour(
            vehicle_id=vehicle_id,
            north=north,
            east=east,
            up=state.alt_rel,
            vn=_bounded(state.vn),
            ve=_bounded(state.ve),
            vu=_bounded(state.climb_rate),
            time=record.last_seen,
        )

    def leader_state(self, formation: ActiveFormation, now: float) -> LeaderState | None:
        """The route's state now (a virtual leader), or the leader vehicle's last report."""
        if formation.plan.leader_id is None:
            v = formation.plan.route.state_at(self._route_time(formation, now))
            return LeaderState(v.north, v.east, v.up, v.vn, v.ve, v.vu, v.heading_rad, now)
        record = self._registry.get(formation.plan.leader_id)
        state, seen = record.state, record.last_seen
        here = self._local(formation, formation.plan.leader_id)
        if state is None or seen is None or here is None:
            return None
        if (now - seen) * self._speedup > MAX_RELAY_AGE_S:  # in the vehicles' seconds
            return None
        heading = math.radians(state.heading_deg or 0.0)
        return LeaderState(
            here.north,
            here.east,
            here.up,
            state.vn or 0.0,
            state.ve or 0.0,
            state.climb_rate or 0.0,
            heading,
            seen,
        )

    def _route_time(self, formation: ActiveFormation, now: float) -> float:
        if formation.formed_at is None:
            return 0.0
        return (now - formation.formed_at) * self._speedup

    def _formed(self, formation: ActiveFormation, leader: LeaderState) -> bool:
        """Every follower within FORM_UP_M of its slot around the leader."""
        return not self._joining(formation, leader)

    def _joining(self, formation: ActiveFormation, leader: LeaderState | None) -> list[str]:
        """Each follower not yet within FORM_UP_M of its slot around the leader, and why."""
        if leader is None:
            return [f"the leader {formation.plan.leader_id}'s state is not known"]
        out = []
        for follower, offset in formation.offsets.items():
            here = self._local(formation, follower)
            if here is None:
                out.append(f"{follower}'s position is not known")
                continue
            (north, east, up), _ = slot_target(leader, offset)
            distance = math.dist((north, east, up), (here.north, here.east, here.up))
            if distance > FORM_UP_M:
                out.append(f"{follower} is {distance:.1f} m from its slot")
        return out

    async def _end_if_not_formed(self, formation: ActiveFormation, now: float) -> bool:
        """Stop (every member holds) a formation still joining past the time limit, naming
        who is not in its slot; whether it did."""
        if formation.formed_at is not None or now - formation.started_at < self._join_timeout_s:
            return False
        why = "; ".join(self._joining(formation, self.leader_state(formation, now)))
        reason = f"did not form within {self._join_timeout_s:g} s: {why or 'not in place'}"
        log.warning("%s %s", formation.id, reason)
        await self.stop(formation.id, reason)
        return True

    async def relay_once(self) -> None:
        now = self._clock()
        for formation in self.active():
            if await self._end_if_not_formed(formation, now):
                continue
            route = formation.plan.route.state_at(self._route_time(formation, now))
            if formation.plan.leader_id is not None:
                # the leader vehicle flies the route itself, at a zero offset
                await self._send(formation.plan.leader_id, _update(formation, route, now, []))
            leader = self.leader_state(formation, now)
            if leader is None:
                continue
            if formation.formed_at is None and self._formed(formation, leader):
                formation.formed_at = now
                log.info("%s formed up: the route starts", formation.id)
            self._measure(formation, leader, now)
            places = [p for v in formation.members if (p := self._local(formation, v))]
            for follower in formation.followers:
                others = [p for p in places if p.vehicle_id != follower]
                await self._send(follower, _update(formation, leader, leader.time_s, others))
            await self._relay_scan(formation, now)

    def _measure(self, formation: ActiveFormation, leader: LeaderState, now: float) -> None:
        """Each follower's error from its slot at the time of its own report, the
        leader carried there at its velocity (at most a second either way)."""
        leg = None
        if formation.formed_at is not None:
            index = formation.plan.route.leg_at(self._route_time(formation, now))
            leg = None if index is None else index + 1
        for follower, offset in formation.offsets.items():
            seen = self._registry.get(follower).last_seen
            here = self._local(formation, follower)
            if seen is None or here is None:
                continue
            dt = max(-1.0, min(1.0, (seen - leader.time_s) * self._speedup))
            then = LeaderState(
                leader.north + leader.vn * dt,
                leader.east + leader.ve * dt,
                leader.up + leader.vu * dt,
                leader.vn,
                leader.ve,
                leader.vu,
                leader.heading_rad,
                seen,
            )
            (north, east, up), _ = slot_target(then, offset)
            error = (here.north - north, here.east - east, here.up - up)
            formation.metrics.record(follower, seen, error, leg)

    async def _relay_scan(self, formation: ActiveFormation, now: float) -> None:
        """The leader vehicle's newest scan to every follower, at most SCAN_RELAY_HZ."""
        leader_id = formation.plan.leader_id
        if leader_id is None or self.scan_source is None:
            return
        if now - formation.scan_relayed_at < 1.0 / SCAN_RELAY_HZ:
            return
        scan = self.scan_source(leader_id, formation.plan.frame, formation.scan_seq)
        if scan is None:
            return
        formation.scan_seq, formation.scan_relayed_at = scan.seq, now
        try:
            message = LeaderScan(
                formation_id=formation.id,
                time=scan.time,
                seq=scan.seq,
                north=list(scan.north),
                east=list(scan.east),
            )
        except ValidationError as error:
            # points beyond the protocol's reach of the formation's origin: not relayed,
            # and the relay of the leader's state goes on
            log.warning("%s: scan %d not relayed: %s", formation.id, scan.seq, error)
            return
        for follower in formation.followers:
            await self._send(follower, message)

    async def run(self) -> None:
        while True:
            await self.relay_once()
            await asyncio.sleep(self._period)


def _update(
    formation: ActiveFormation, leader: LeaderState, time_s: float, others: list[Neighbour]
) -> LeaderUpdate:
    return LeaderUpdate(
        formation_id=formation.id,
        time=time_s,
        north=leader.north,
        east=leader.east,
        up=leader.up,
        vn=leader.vn,
        ve=leader.ve,
        vu=leader.vu,
        heading_deg=math.degrees(leader.heading_rad) % 360.0,
        neighbours=others,
    )


def _bounded(speed: float | None) -> float:
    """A reported speed within the protocol's bounds (a glitching sensor's value must
    not stop the relay)."""
    if speed is None or not math.isfinite(speed):
        return 0.0
    return max(-99.0, min(99.0, speed))
