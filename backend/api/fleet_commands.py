"""Group commands: one call, the same command to a selection of vehicles or the fleet."""

from __future__ import annotations

import asyncio
from typing import Annotated, Any

from fastapi import Query, Request
from pydantic import BaseModel, Field

from backend.api.deps import CommandServicesDep
from backend.api.security import CurrentPrincipal, SecuredRouter, client_address, requires
from backend.api.vehicle_budget import VehicleBudgetDep
from backend.auth.policy import Permission, Principal, authorize
from backend.errors import GcsError, InvalidRequest, SafetyViolation
from backend.fleet.collaborators import CommandServices
from backend.fleet.command_service import execute_command
from backend.fleet.registry import FleetRegistry
from protocol.messages import ClientCommand, Command, CommandOutcome, VehicleId

router = SecuredRouter(prefix="/fleet", tags=["vehicles"])

# The design's fleet size: one call can still reach every vehicle of a full fleet.
MAX_GROUP = 1000
# Unknown ids named in a refusal; the rest are counted.
NAMED_UNKNOWN = 10


class GroupCommandRequest(BaseModel):
    vehicle_ids: list[VehicleId] | None = Field(
        default=None,
        min_length=1,
        max_length=MAX_GROUP,
        description="The selection; every connected vehicle when unset",
    )
    command: ClientCommand


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
    commands: CommandServicesDep,
    budget: VehicleBudgetDep,
    override_reason: Annotated[
        str | None,
        Query(min_length=10, max_length=500, description="Admins only, as for one vehicle"),
    ] = None,
) -> GroupCommandResponse:
    """Send one command to many vehicles at once, concurrently; one result per vehicle.

    Each vehicle goes through the same checks as a single command (policy, safety
    rails, audit), so one refusal does not hold back the others. A selection naming
    a vehicle the hub does not know is refused whole (422), before anything is sent.
    Each vehicle reached counts as one command in the caller's rate limit; a call is
    accepted while the caller has budget left, so a fleet-wide RTL is never split.
    """
    budget.check(principal)
    if body.vehicle_ids is not None:
        targets = list(dict.fromkeys(body.vehicle_ids))
        _refuse_unknown(commands.registry, targets)
    else:
        targets = [r.id for r in commands.registry.all() if r.connected]
    budget.spend(principal, len(targets))
    source = client_address(request)
    results = await asyncio.gather(
        *(
            _one(commands, principal, source, vehicle, body.command, override_reason)
            for vehicle in targets
        )
    )
    return GroupCommandResponse(command=body.command, results=list(results))


def _refuse_unknown(registry: FleetRegistry, targets: list[str]) -> None:
    """One answer for the whole selection, instead of a refusal and an audit entry per
    made-up id."""
    known = {record.id for record in registry.all()}
    unknown = [vehicle for vehicle in targets if vehicle not in known]
    if unknown:
        named = ", ".join(unknown[:NAMED_UNKNOWN])
        more = f" and {len(unknown) - NAMED_UNKNOWN} more" if len(unknown) > NAMED_UNKNOWN else ""
        raise InvalidRequest("vehicle_ids", f"unknown vehicles: {named}{more}")


async def _one(
    commands: CommandServices,
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
            commands, principal, source, vehicle_id, command, override_reason
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
