"""Formations in flight: start one (checked), change its shape, stop it, store each, and
relay the leader's state to the followers at ``rate_hz`` (``backend.formation.relay``)."""

from __future__ import annotations

import asyncio
import json
import logging
import secrets
import time
from collections.abc import Callable

from sqlalchemy.exc import SQLAlchemyError
from starlette.websockets import WebSocketDisconnect

from backend.errors import Conflict, NotFound
from backend.fleet.airborne import not_airborne
from backend.fleet.registry import FleetRegistry
from backend.formation.active import ActiveFormation
from backend.formation.metrics import tracking_summary
from backend.formation.planner import check_separation, follower_offsets, plan_formation
from backend.formation.relay import FormationRelay, ScanSource
from backend.formation.schemas import FormationRequest, ShapeChange
from backend.formation.slots import slot_messages
from backend.formation.store import FormationRepository, StoredFormation
from backend.safety.service import SafetyService
from backend.safety.snapshot import snapshot_of
from common.formation import LeaderState
from protocol.messages import FormationEnd, Message

log = logging.getLogger(__name__)

# A formation whose followers have not all reached their slots this long after it started
# ends (its members hold) with the reason, rather than sit "joining" for ever.
JOIN_TIMEOUT_S = 60.0


class FormationService:
    def __init__(
        self,
        registry: FleetRegistry,
        safety: SafetyService,
        rate_hz: float = 10.0,
        clock: Callable[[], float] = time.time,
        repository: FormationRepository | None = None,
        join_timeout_s: float = JOIN_TIMEOUT_S,
        scan_source: ScanSource | None = None,
        speedup: float = 1.0,
    ) -> None:
        self._registry = registry
        self._join_timeout_s = join_timeout_s
        self._safety = safety
        self._repository = repository
        # A simulated fleet's speed-up (its seconds per wall second, one for the whole
        # fleet; 1 for aircraft): the route, the relay's rate and the ages the hub
        # reckons run in the vehicles' seconds, as their agents' followers do. The stamps
        # stay Unix time, the one clock every member shares.
        self._period = 1.0 / (rate_hz * speedup)
        self._speedup = speedup
        self._clock = clock
        self._formations: dict[str, ActiveFormation] = {}
        self._relay = FormationRelay(registry, self._send, scan_source, speedup)

    def now(self) -> float:
        """The hub's clock, as the formations' times are stamped."""
        return self._clock()

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
            speedup=self._speedup,
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
        for vehicle_id, slot in slot_messages(formation).items():
            await self._send(vehicle_id, slot)

    async def _send(self, vehicle_id: str, message: Message) -> None:
        channel = self._registry.get(vehicle_id).channel
        if channel is None:
            return  # offline: its agent holds on the stale leader state
        try:
            await channel.send_frame(message)
        except (RuntimeError, OSError, WebSocketDisconnect) as error:
            log.info("formation message to %s not sent: %s", vehicle_id, error)

    # -- the relay -------------------------------------------------------------

    def leader_state(self, formation: ActiveFormation, now: float) -> LeaderState | None:
        """The route's state now (a virtual leader), or the leader vehicle's last report."""
        return self._relay.leader_state(formation, now)

    async def _end_if_not_formed(self, formation: ActiveFormation, now: float) -> bool:
        """Stop (every member holds) a formation still joining past the time limit, naming
        who is not in its slot; whether it did."""
        if formation.formed_at is not None or now - formation.started_at < self._join_timeout_s:
            return False
        why = "; ".join(self._relay.joining(formation, self.leader_state(formation, now)))
        reason = f"did not form within {self._join_timeout_s:g} s: {why or 'not in place'}"
        log.warning("%s %s", formation.id, reason)
        await self.stop(formation.id, reason)
        return True

    async def relay_once(self) -> None:
        now = self._clock()
        for formation in self.active():
            if not await self._end_if_not_formed(formation, now):
                await self._relay.relay(formation, now)

    async def run(self) -> None:
        while True:
            await self.relay_once()
            await asyncio.sleep(self._period)
