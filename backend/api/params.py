"""A vehicle's parameters, read from and written to its flight controller."""

from __future__ import annotations

from typing import Annotated

from fastapi import Path, Request
from pydantic import BaseModel, Field

from backend.api.deps import CommandServicesDep
from backend.api.security import CurrentPrincipal, SecuredRouter, client_address, requires
from backend.api.vehicle_budget import VehicleBudget, VehicleBudgetDep
from backend.auth.policy import Permission
from backend.fleet.command_service import execute_expecting_acceptance
from protocol.messages import (
    Command,
    Float32,
    ParamGetCommand,
    ParamListCommand,
    ParamMeta,
    ParamName,
    ParamSetCommand,
    VehicleId,
)

router = SecuredRouter(prefix="/vehicles/{vehicle_id}/params", tags=["parameters"])

VehicleIdPath = Annotated[VehicleId, Path()]
ParamPath = Annotated[ParamName, Path()]


class ParamValues(BaseModel):
    vehicle_id: str
    values: dict[str, float]
    metadata: ParamMeta | None = Field(
        default=None,
        description="For one parameter read or written: what it means, from the autopilot's "
        "own metadata (PX4 publishes it; the agent reads it over MAVLink FTP). Absent when "
        "the autopilot publishes none (ArduPilot) or it has not been read yet.",
    )
    range_checked: bool | None = Field(
        default=None,
        description="For a write: true if the value was checked against the metadata's range "
        "and values before it was sent (a value outside them is a 409 naming them); false if "
        "there was no metadata to check it against, so only the vehicle's own answer counted.",
    )


class ParamUpdate(BaseModel):
    # PARAM_SET carries a float32: a value it cannot hold is a 422 here, not an error
    # inside the vehicle's agent.
    value: Float32


async def _ask(
    commands: CommandServicesDep,
    budget: VehicleBudget,
    request: Request,
    principal: CurrentPrincipal,
    vehicle_id: str,
    command: Command,
) -> ParamValues:
    budget.spend(principal)
    outcome = await execute_expecting_acceptance(
        commands, principal, client_address(request), vehicle_id, command
    )
    checked = (outcome.param_meta is not None) if isinstance(command, ParamSetCommand) else None
    return ParamValues(
        vehicle_id=vehicle_id,
        values=outcome.values or {},
        metadata=outcome.param_meta,
        range_checked=checked,
    )


@router.get("", response_model=ParamValues, openapi_extra=requires(Permission.READ))
async def list_params(
    vehicle_id: VehicleIdPath,
    request: Request,
    principal: CurrentPrincipal,
    commands: CommandServicesDep,
    budget: VehicleBudgetDep,
) -> ParamValues:
    """Every parameter of the vehicle, read from its flight controller."""
    return await _ask(commands, budget, request, principal, vehicle_id, ParamListCommand())


@router.get("/{param}", response_model=ParamValues, openapi_extra=requires(Permission.READ))
async def get_param(
    vehicle_id: VehicleIdPath,
    param: ParamPath,
    request: Request,
    principal: CurrentPrincipal,
    commands: CommandServicesDep,
    budget: VehicleBudgetDep,
) -> ParamValues:
    return await _ask(
        commands, budget, request, principal, vehicle_id, ParamGetCommand(param=param)
    )


@router.put("/{param}", response_model=ParamValues, openapi_extra=requires(Permission.COMMAND))
async def set_param(
    vehicle_id: VehicleIdPath,
    param: ParamPath,
    body: ParamUpdate,
    request: Request,
    principal: CurrentPrincipal,
    commands: CommandServicesDep,
    budget: VehicleBudgetDep,
) -> ParamValues:
    """Set a parameter; succeeds only when the flight controller echoes the new value
    (409 with the value it kept otherwise, e.g. out of its range). Where the autopilot
    publishes parameter metadata (PX4), a value outside its range or its values is a 409
    naming them, and is never sent; `range_checked` says whether that check was made."""
    command = ParamSetCommand(param=param, value=body.value)
    return await _ask(commands, budget, request, principal, vehicle_id, command)
