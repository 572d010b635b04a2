"""Formation missions: start one, change its shape or spacing in flight, stop it.

The checks and the relay are `backend.fleet.formations`; a refusal names its reason (422)."""

from __future__ import annotations

from typing import Annotated

from fastapi import Path
from pydantic import BaseModel, Field

from backend.api.deps import HubDep
from backend.api.security import SecuredRouter, requires
from backend.auth.policy import Permission
from backend.fleet.formations import ActiveFormation
from backend.missions.formation.schemas import FormationRequest, OffsetModel, ShapeChange
from common.formation import Controller

router = SecuredRouter(prefix="/formations", tags=["formations"])

FormationIdPath = Annotated[str, Path(pattern=r"^[A-Za-z0-9_.-]{1,64}$")]


class FormationStatus(BaseModel):
    id: str
    leader_id: str | None = Field(description="Null for a virtual leader")
    slots: dict[str, OffsetModel] = Field(description="Each follower's slot")
    started_at: float = Field(description="Unix time the formation started")
    formed_at: float | None = Field(
        description="Unix time every follower reached its slot and the route's clock "
        "started; null while they join"
    )
    route_duration_s: float
    controller: Controller
    stopped: str | None = Field(description="Why it stopped; null while it flies")

    @classmethod
    def of(cls, formation: ActiveFormation) -> FormationStatus:
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
            controller=formation.plan.controller,
            stopped=formation.stopped,
        )


@router.post("", response_model=FormationStatus, openapi_extra=requires(Permission.COMMAND))
async def start_formation(body: FormationRequest, hub: HubDep) -> FormationStatus:
    """Check the formation (separation of every slot, roles, readiness, speed, and the
    route with every slot around it against the rails) and start it: each member gets its
    slot, and the leader's state is relayed to the followers at 10 Hz."""
    return FormationStatus.of(await hub.formations.start(body))


@router.get(
    "/{formation_id}", response_model=FormationStatus, openapi_extra=requires(Permission.READ)
)
async def get_formation(formation_id: FormationIdPath, hub: HubDep) -> FormationStatus:
    return FormationStatus.of(hub.formations.get(formation_id))


@router.patch(
    "/{formation_id}", response_model=FormationStatus, openapi_extra=requires(Permission.COMMAND)
)
async def change_formation(
    formation_id: FormationIdPath, body: ShapeChange, hub: HubDep
) -> FormationStatus:
    """A new shape or spacing in flight; the followers glide to their new slots."""
    return FormationStatus.of(await hub.formations.change_shape(formation_id, body))


@router.post(
    "/{formation_id}/stop",
    response_model=FormationStatus,
    openapi_extra=requires(Permission.COMMAND),
)
async def stop_formation(formation_id: FormationIdPath, hub: HubDep) -> FormationStatus:
    """Every member leaves the formation and holds where it is."""
    await hub.formations.stop(formation_id)
    return FormationStatus.of(hub.formations.get(formation_id))
