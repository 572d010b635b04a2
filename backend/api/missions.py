"""A vehicle's mission: upload (checked against the safety rails first), download, clear,
and the current item."""

from __future__ import annotations

from typing import Annotated

from fastapi import Path, Query, Request
from pydantic import BaseModel, Field

from backend.api.deps import CommandServicesDep, MissionViewsDep
from backend.api.security import CurrentPrincipal, SecuredRouter, client_address, requires
from backend.api.vehicle_budget import VehicleBudget, VehicleBudgetDep
from backend.auth.policy import Permission
from backend.fleet.command_service import execute_expecting_acceptance
from backend.safety.mission_schemas import Mission
from protocol.messages import (
    Command,
    CommandOutcome,
    Integer,
    MissionClearCommand,
    MissionDownloadCommand,
    MissionItem,
    MissionSetCurrentCommand,
    MissionUploadCommand,
    VehicleId,
)

router = SecuredRouter(prefix="/vehicles/{vehicle_id}/mission", tags=["missions"])

VehicleIdPath = Annotated[VehicleId, Path()]
OverrideQuery = Annotated[
    str | None,
    Query(min_length=10, max_length=500, description="Admins only, as for commands (audited)"),
]


class CurrentItem(BaseModel):
    seq: Integer = Field(ge=1, le=2000)


class MissionResult(BaseModel):
    vehicle_id: str
    outcome: CommandOutcome
    items: list[MissionItem] | None = None


async def _run(
    commands: CommandServicesDep,
    budget: VehicleBudget,
    request: Request,
    principal: CurrentPrincipal,
    vehicle_id: str,
    command: Command,
    override_reason: str | None = None,
) -> MissionResult:
    budget.spend(principal)
    outcome = await execute_expecting_acceptance(
        commands, principal, client_address(request), vehicle_id, command, override_reason
    )
    return MissionResult(vehicle_id=vehicle_id, outcome=outcome, items=outcome.items)


@router.post("", response_model=MissionResult, openapi_extra=requires(Permission.COMMAND))
async def upload_mission(
    vehicle_id: VehicleIdPath,
    body: Mission,
    request: Request,
    principal: CurrentPrincipal,
    commands: CommandServicesDep,
    budget: VehicleBudgetDep,
    missions: MissionViewsDep,
    override_reason: OverrideQuery = None,
) -> MissionResult:
    """Replace the vehicle's mission. The mission check runs first (the body and the
    rules are those of `mission-check`): every item problem and every rail it breaks is
    listed (422) before anything reaches the vehicle; a vehicle that rejects an item keeps
    its previous mission (409)."""
    command = MissionUploadCommand(items=body.items)
    result = await _run(commands, budget, request, principal, vehicle_id, command, override_reason)
    await missions.mission_known(vehicle_id, body.items)
    return result


@router.get("", response_model=MissionResult, openapi_extra=requires(Permission.READ))
async def download_mission(
    vehicle_id: VehicleIdPath,
    request: Request,
    principal: CurrentPrincipal,
    commands: CommandServicesDep,
    budget: VehicleBudgetDep,
    missions: MissionViewsDep,
) -> MissionResult:
    """The mission on the vehicle now (item 0 is home)."""
    result = await _run(commands, budget, request, principal, vehicle_id, MissionDownloadCommand())
    if result.items is not None:
        await missions.mission_known(vehicle_id, result.items[1:])
    return result


@router.delete("", response_model=MissionResult, openapi_extra=requires(Permission.COMMAND))
async def clear_mission(
    vehicle_id: VehicleIdPath,
    request: Request,
    principal: CurrentPrincipal,
    commands: CommandServicesDep,
    budget: VehicleBudgetDep,
    missions: MissionViewsDep,
) -> MissionResult:
    result = await _run(commands, budget, request, principal, vehicle_id, MissionClearCommand())
    await missions.mission_known(vehicle_id, [])
    return result


@router.put("/current", response_model=MissionResult, openapi_extra=requires(Permission.COMMAND))
async def set_current_item(
    vehicle_id: VehicleIdPath,
    body: CurrentItem,
    request: Request,
    principal: CurrentPrincipal,
    commands: CommandServicesDep,
    budget: VehicleBudgetDep,
) -> MissionResult:
    """Fly on from item ``seq`` (1 is the first after home). An item beyond the mission
    on board is refused at once (422, naming the mission's length)."""
    command = MissionSetCurrentCommand(seq=body.seq)
    return await _run(commands, budget, request, principal, vehicle_id, command)
