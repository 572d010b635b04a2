"""The safety routes: the site's rails, per-vehicle overrides, and the pre-flight checks
of a mission and of a go-to. They reach the hub's parts through `dependencies` only."""

from __future__ import annotations

import asyncio
from typing import Annotated

from fastapi import Path, Request, Response, status
from pydantic import BaseModel, ConfigDict, Field

from backend.api.security import CurrentPrincipal, SecuredRouter, audit_entry, requires
from backend.audit import AuditAction
from backend.auth.policy import Permission
from backend.safety.dependencies import AuditLogDep, SafetyDep, VehiclesDep
from backend.safety.mission_schemas import Mission, MissionCheckResponse
from backend.safety.rails_store import SITE
from backend.safety.schemas import SafetyRailsModel, ViolationModel
from backend.safety.snapshot import position, snapshot_of
from common.geodesy import haversine_m
from protocol.messages import GotoCommand, Number, VehicleId

router = SecuredRouter(tags=["safety"])

VehicleIdPath = Annotated[VehicleId, Path()]


@router.get(
    "/safety/rails", response_model=SafetyRailsModel, openapi_extra=requires(Permission.READ)
)
async def site_rails(safety: SafetyDep) -> SafetyRailsModel:
    """The site's rails, which apply to every vehicle unless narrowed per vehicle."""
    return SafetyRailsModel.from_rails(await asyncio.to_thread(safety.site_rails))


@router.put(
    "/safety/rails", response_model=SafetyRailsModel, openapi_extra=requires(Permission.ADMIN)
)
async def set_site_rails(
    body: SafetyRailsModel,
    request: Request,
    principal: CurrentPrincipal,
    safety: SafetyDep,
    audit: AuditLogDep,
) -> SafetyRailsModel:
    await asyncio.to_thread(safety.store_site_rails, body, principal.name)
    await audit.record(
        audit_entry(
            request, principal, AuditAction.RAILS_UPDATE, SITE, "ok", rails=body.model_dump()
        )
    )
    return body


@router.get(
    "/vehicles/{vehicle_id}/safety-rails",
    response_model=SafetyRailsModel,
    openapi_extra=requires(Permission.READ),
)
async def effective_vehicle_rails(
    vehicle_id: VehicleIdPath, safety: SafetyDep, vehicles: VehiclesDep
) -> SafetyRailsModel:
    """The rails in force for this vehicle: the site's, with its own overrides applied."""
    vehicles.get(vehicle_id)
    return SafetyRailsModel.from_rails(await asyncio.to_thread(safety.effective_rails, vehicle_id))


@router.put(
    "/vehicles/{vehicle_id}/safety-rails",
    response_model=SafetyRailsModel,
    openapi_extra=requires(Permission.ADMIN),
)
async def set_vehicle_rails(
    vehicle_id: VehicleIdPath,
    body: SafetyRailsModel,
    request: Request,
    principal: CurrentPrincipal,
    safety: SafetyDep,
    vehicles: VehiclesDep,
    audit: AuditLogDep,
) -> SafetyRailsModel:
    """Per-vehicle rails: each value set here replaces the site's for this vehicle."""
    vehicles.get(vehicle_id)
    await asyncio.to_thread(safety.store_vehicle_rails, vehicle_id, body, principal.name)
    await audit.record(
        audit_entry(
            request, principal, AuditAction.RAILS_UPDATE, vehicle_id, "ok", rails=body.model_dump()
        )
    )
    return body


@router.delete(
    "/vehicles/{vehicle_id}/safety-rails",
    status_code=status.HTTP_204_NO_CONTENT,
    openapi_extra=requires(Permission.ADMIN),
)
async def clear_vehicle_rails(
    vehicle_id: VehicleIdPath,
    request: Request,
    principal: CurrentPrincipal,
    safety: SafetyDep,
    vehicles: VehiclesDep,
    audit: AuditLogDep,
) -> Response:
    vehicles.get(vehicle_id)
    await asyncio.to_thread(safety.clear_vehicle_rails, vehicle_id)
    await audit.record(audit_entry(request, principal, AuditAction.RAILS_CLEAR, vehicle_id, "ok"))
    return Response(status_code=status.HTTP_204_NO_CONTENT)


@router.post(
    "/vehicles/{vehicle_id}/mission-check",
    response_model=MissionCheckResponse,
    openapi_extra=requires(Permission.COMMAND),
)
async def check_mission(
    vehicle_id: VehicleIdPath, body: Mission, safety: SafetyDep, vehicles: VehiclesDep
) -> MissionCheckResponse:
    """Check a mission before it flies: what each item's command needs (rule
    `mission_item`), every rail its places break, and the battery estimate. The body is
    the upload's; upload and a switch to AUTO run the same check and refuse on any
    violation (422)."""
    record = vehicles.get(vehicle_id)
    check = await asyncio.to_thread(safety.check_mission, record, body.items)
    return MissionCheckResponse.from_plan_check(check)


class GotoCheck(BaseModel):
    """A go-to to check: the `goto` command's fields."""

    model_config = ConfigDict(extra="forbid", allow_inf_nan=False)

    lat: Number = Field(ge=-90, le=90)
    lon: Number = Field(ge=-180, le=180)
    altitude: Number = Field(gt=0.5, le=500, description="Metres above home")


class GotoCheckResponse(BaseModel):
    ok: bool = Field(description="True when the go-to breaks no rule")
    violations: list[ViolationModel]
    distance_m: float | None = Field(
        description="Horizontal distance from the vehicle to the target; null when the "
        "vehicle's position is not known"
    )


@router.post(
    "/vehicles/{vehicle_id}/goto-check",
    response_model=GotoCheckResponse,
    openapi_extra=requires(Permission.COMMAND),
)
async def check_goto(
    vehicle_id: VehicleIdPath, body: GotoCheck, safety: SafetyDep, vehicles: VehiclesDep
) -> GotoCheckResponse:
    """Check a go-to without sending it: the same rails the `goto` command is held to
    (the geofence, the way there, the altitude limits, the range from home)."""
    record = vehicles.get(vehicle_id)
    command = GotoCommand(lat=body.lat, lon=body.lon, altitude=body.altitude)
    violations = await asyncio.to_thread(safety.check_command, record, command)
    here = position(snapshot_of(record))
    return GotoCheckResponse(
        ok=not violations,
        violations=[ViolationModel.from_violation(v) for v in violations],
        distance_m=None if here is None else haversine_m(here.lat, here.lon, body.lat, body.lon),
    )
