"""Formation missions: start one, change its shape or spacing in flight, stop it.

The checks are `backend.formation.planner`, the relay `backend.formation.relay`; a refusal
names its reason (422). The routes reach the service through `FormationServiceDep`."""

from __future__ import annotations

import asyncio
import json
from collections.abc import AsyncIterator
from contextlib import asynccontextmanager
from typing import Annotated, Any

from fastapi import Path, Query, Request
from pydantic import BaseModel, Field

from backend.api.deps import AuditLogDep
from backend.api.security import CurrentPrincipal, SecuredRouter, audit_entry, requires
from backend.audit import AuditAction, AuditLog
from backend.auth.policy import Permission, Principal
from backend.errors import GcsError
from backend.formation.active import ActiveFormation, FormationState
from backend.formation.deps import FormationServiceDep
from backend.formation.metrics import ErrorStats, FollowerTracking
from backend.formation.schemas import FormationRequest, OffsetModel, ShapeChange
from common.formation import Controller

router = SecuredRouter(prefix="/formations", tags=["formations"])

FormationIdPath = Annotated[str, Path(pattern=r"^[A-Za-z0-9_.-]{1,64}$")]


class ErrorStatsModel(BaseModel):
    samples: int = Field(description="Follower reports measured")
    rms_xy_m: float
    max_xy_m: float
    rms_z_m: float
    max_z_m: float

    @classmethod
    def of(cls, stats: ErrorStats) -> ErrorStatsModel:
        return cls(
            samples=stats.samples,
            rms_xy_m=stats.rms_xy_m,
            max_xy_m=stats.max_xy_m,
            rms_z_m=stats.rms_z_m,
            max_z_m=stats.max_z_m,
        )


class TrackingModel(BaseModel):
    live_xy_m: float | None = Field(description="The newest horizontal error from its slot")
    live_z_m: float | None = Field(description="The newest vertical error")
    legs: dict[int, ErrorStatsModel] = Field(
        description="Per leg of the route (numbered from 1), while the leader flies it"
    )
    mission: ErrorStatsModel = Field(description="Over every leg so far")

    @classmethod
    def of(cls, tracking: FollowerTracking) -> TrackingModel:
        return cls(
            live_xy_m=tracking.live_xy_m,
            live_z_m=tracking.live_z_m,
            legs={leg: ErrorStatsModel.of(s) for leg, s in sorted(tracking.legs.items())},
            mission=ErrorStatsModel.of(tracking.mission),
        )


class FormationStatus(BaseModel):
    id: str
    leader_id: str | None = Field(description="Null for a virtual leader")
    slots: dict[str, OffsetModel] = Field(description="Each follower's slot")
    started_at: float = Field(description="Unix time the formation started")
    formed_at: float | None = Field(
        description="Unix time every follower reached its slot and the route's clock "
        "started; null while they join"
    )
    route_duration_s: float = Field(description="The route's length in the fleet's seconds")
    state: FormationState = Field(
        description="joining: the followers make for their slots; flying: the leader flies "
        "the route; route_done: it reached the route's last waypoint and the formation "
        "holds there until stopped; stopped: ended (see `stopped`)"
    )
    route_done_at: float | None = Field(
        description="Unix time the leader reaches the route's last waypoint (in the future "
        "while flying); null while joining, or when it stopped before the end"
    )
    controller: Controller
    tracking: dict[str, TrackingModel] = Field(
        description="Each follower's error from its slot (the leader carried to the time "
        "of the follower's report): live, and RMS and maximum per leg and over the mission"
    )
    stopped: str | None = Field(description="Why it stopped; null while it flies")

    @classmethod
    def of(cls, formation: ActiveFormation, now: float) -> FormationStatus:
        return cls(
            id=formation.id,
            leader_id=formation.plan.leader_id,
            slots={
                v: OffsetModel(x=o.x, y=o.y, up=o.up, frame=o.frame)
                for v, o in formation.offsets.items()
            },
            started_at=formation.started_at,
            formed_at=formation.formed_at,
            route_duration_s=formation.plan.route.duration_s,
            state=formation.state(now),
            route_done_at=formation.route_done_at,
            controller=formation.plan.controller,
            tracking={v: TrackingModel.of(t) for v, t in formation.metrics.followers.items()},
            stopped=formation.stopped,
        )


@router.post("", response_model=FormationStatus, openapi_extra=requires(Permission.COMMAND))
async def start_formation(
    body: FormationRequest,
    request: Request,
    principal: CurrentPrincipal,
    formations: FormationServiceDep,
    audit: AuditLogDep,
) -> FormationStatus:
    """Check the formation (separation of every slot, roles, readiness, speed, and the
    route with every slot around it against the rails) and start it: each member gets its
    slot, and the leader's state is relayed to the followers at 10 Hz. Audited, refused
    or not.

    Every member must already fly (armed, and in the air by its autopilot's landed state):
    the hub does not take members off. One that is on the ground, landing, disarmed or
    whose landed state is unknown is refused (422, each named: "sim_3 is on the ground:
    take off first") before any member is told anything. A formation whose followers are
    not all in their slots within the hub's join time limit (GCS_FORMATION_JOIN_TIMEOUT_S,
    60 s) ends with the reason in `stopped`, and every member holds."""
    target = body.leader_id or "virtual leader"
    async with _audited(request, principal, audit, AuditAction.FORMATION_START, target) as note:
        formation = await formations.start(body, by=principal.name)
        note.update(
            formation_id=formation.id,
            followers=formation.followers,
            controller=formation.plan.controller.value,
        )
    return FormationStatus.of(formation, formations.now())


class StoredFormationModel(BaseModel):
    id: str
    started: float = Field(description="Unix time")
    started_by: str
    leader_id: str | None
    request: dict[str, Any] = Field(
        description="The formation as started (its shape and spacing as last changed)"
    )
    stopped: float | None
    stopped_by: str | None = Field(description="Null when the formation ended otherwise")
    stop_reason: str | None
    tracking: dict[str, Any] | None = Field(
        description="Per follower: RMS and maximum errors per leg and over the mission, "
        "as they stood when it stopped"
    )


class StoredFormations(BaseModel):
    formations: list[StoredFormationModel]


@router.get("", response_model=StoredFormations, openapi_extra=requires(Permission.READ))
async def list_formations(
    formations: FormationServiceDep, limit: Annotated[int, Query(ge=1, le=500)] = 50
) -> StoredFormations:
    """The latest formations as stored, newest first: who started and stopped each, what
    it flew, and its tracking figures."""
    stored = await asyncio.to_thread(formations.stored, limit)
    return StoredFormations(
        formations=[
            StoredFormationModel(
                id=f.id,
                started=f.started,
                started_by=f.started_by,
                leader_id=f.leader_id,
                request=json.loads(f.request_json),
                stopped=f.stopped,
                stopped_by=f.stopped_by,
                stop_reason=f.stop_reason,
                tracking=None if f.tracking_json is None else json.loads(f.tracking_json),
            )
            for f in stored
        ]
    )


@router.get(
    "/{formation_id}", response_model=FormationStatus, openapi_extra=requires(Permission.READ)
)
async def get_formation(
    formation_id: FormationIdPath, formations: FormationServiceDep
) -> FormationStatus:
    return FormationStatus.of(formations.get(formation_id), formations.now())


@router.patch(
    "/{formation_id}", response_model=FormationStatus, openapi_extra=requires(Permission.COMMAND)
)
async def change_formation(
    formation_id: FormationIdPath,
    body: ShapeChange,
    request: Request,
    principal: CurrentPrincipal,
    formations: FormationServiceDep,
    audit: AuditLogDep,
) -> FormationStatus:
    """A new shape or spacing in flight; the followers glide to their new slots."""
    action = AuditAction.FORMATION_CHANGE
    async with _audited(request, principal, audit, action, formation_id) as note:
        note.update(body.model_dump(exclude_none=True, mode="json"))
        formation = await formations.change_shape(formation_id, body)
    return FormationStatus.of(formation, formations.now())


@router.post(
    "/{formation_id}/stop",
    response_model=FormationStatus,
    openapi_extra=requires(Permission.COMMAND),
)
async def stop_formation(
    formation_id: FormationIdPath,
    request: Request,
    principal: CurrentPrincipal,
    formations: FormationServiceDep,
    audit: AuditLogDep,
) -> FormationStatus:
    """Every member leaves the formation and holds where it is."""
    async with _audited(request, principal, audit, AuditAction.FORMATION_STOP, formation_id):
        await formations.stop(formation_id, by=principal.name)
    return FormationStatus.of(formations.get(formation_id), formations.now())


@asynccontextmanager
async def _audited(
    request: Request, principal: Principal, audit: AuditLog, action: AuditAction, target: str
) -> AsyncIterator[dict[str, Any]]:
    """Record who did ``action`` on ``target`` and how it ended: ok, or refused with the
    reason (the refusal still reaches the caller)."""
    detail: dict[str, Any] = {}
    try:
        yield detail
    except GcsError as refusal:
        entry = audit_entry(
            request, principal, action, target, "refused", reason=refusal.message, **detail
        )
        await asyncio.to_thread(audit.record, entry)
        raise
    await asyncio.to_thread(
        audit.record, audit_entry(request, principal, action, target, "ok", **detail)
    )
