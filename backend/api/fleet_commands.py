"""Group commands: one call, the same command to a selection of vehicles or the fleet."""

from __future__ import annotations

import asyncio
from typing import Annotated, Any

from fastapi import Query, Request
from pydantic import BaseModel, Field

from backend.api.deps import HubDep
from backend.api.security import CurrentPrincipal, SecuredRouter, client_address, requires
from backend.auth.policy import Permission, Principal, authorize
from backend.errors import GcsError, SafetyViolation
from backend.fleet.command_service import execute_command
from backend.hub import Hub
from gcs.protocol import Command, CommandOutcome, VehicleId

router = SecuredRouter(prefix="/fleet", tags=["vehicles"])

MAX_GROUP = 1000


class GroupCommandRequest(BaseModel):
    vehicle_ids: list[VehicleId] | None = Field(
        default=None,
        min_length=1,
        max_length=MAX_GROUP,
        description="The selection; every connected vehicle when unset",
    )
    command: Command


class VehicleCommandResult(BaseModel):
    vehicle_id: str
    status_code: int = Field(description="What a single-vehicle call would have returned")
    outcome: CommandOutcome | None = None
    error: str | None = None
    violations: list[dict[str, Any]] | None = None


class GroupCommandResponse(BaseModel):
    command: Command
    results: list[VehicleCommandResult]


@router.post(
    "/commands", response_model=GroupCommandResponse, openapi_extra=requires(Permission.COMMAND)
)
async def send_group_command(
    body: GroupCommandRequest,
    request: Request,
    principal: CurrentPrincipal,
    hub: HubDep,
    override_reason: Annotated[
        str | None,
        Query(min_length=10, max_length=500, description="Admins only, as for one vehicle"),
    ] = None,
) -> GroupCommandResponse:
    """Send one command to many vehicles at once, concurrently; one result per vehicle.

    Each vehicle goes through the same checks as a single command (policy, safety
    rails, audit), so one refusal does not hold back the others.
    """
    hub.command_limiter.check(principal.name, "commands")
    hub.command_limiter.hit(principal.name)
    if body.vehicle_ids is not None:
        targets = list(dict.fromkeys(body.vehicle_ids))
    else:
        targets = [r.id for r in hub.registry.all() if r.connected]
    source = client_address(request)
    results = await asyncio.gather(
        *(
            _one(hub, principal, source, vehicle, body.command, override_reason)
            for vehicle in targets
        )
    )
    return GroupCommandResponse(command=body.command, results=list(results))


async def _one(
    hub: Hub,
    principal: Principal,
    source: str,
    vehicle_id: str,
    command: Command,
    override_reason: str | None,
) -> VehicleCommandResult:
    try:
        # Per vehicle: a rule such as a control lease applies to each one separately.
        authorize(principal, Permission.COMMAND, vehicle_id)
        outcome = await execute_command(
            hub, principal, source, vehicle_id, command, override_reason
        )
    except SafetyViolation as refusal:
        return VehicleCommandResult(
            vehicle_id=vehicle_id,
            status_code=refusal.status_code,
            error=refusal.message,
            violations=refusal.violations,
        )
    except GcsError as error:
        return VehicleCommandResult(
            vehicle_id=vehicle_id, status_code=error.status_code, error=error.message
        )
    return VehicleCommandResult(vehicle_id=vehicle_id, status_code=200, outcome=outcome)
