"""Vehicles: live state, commands, telemetry history."""

from __future__ import annotations

import asyncio
from typing import Annotated

from fastapi import Body, Path, Query, Request

from backend.api.deps import CommandServicesDep, RegistryDep, RepositoryDep
from backend.api.schemas import CommandResponse, TelemetryPage, TelemetrySample
from backend.api.security import CurrentPrincipal, SecuredRouter, client_address, requires
from backend.api.time_ranges import Moment, time_query, time_range
from backend.api.vehicle_budget import VehicleBudgetDep
from backend.auth.policy import Permission
from backend.fleet.command_service import execute_command
from protocol.messages import ClientCommand, VehicleSummary

router = SecuredRouter(prefix="/vehicles", tags=["vehicles"])

VehicleIdPath = Annotated[str, Path(description="The vehicle's identity", max_length=64)]
MAX_TELEMETRY_PAGE = 10_000
DEFAULT_HISTORY_S = 600.0


@router.get("", response_model=list[VehicleSummary], openapi_extra=requires(Permission.READ))
async def list_vehicles(registry: RegistryDep) -> list[VehicleSummary]:
    """Every known vehicle with its live state (connected or not)."""
    return [record.summary() for record in registry.all()]


@router.get("/{vehicle_id}", response_model=VehicleSummary, openapi_extra=requires(Permission.READ))
async def get_vehicle(vehicle_id: VehicleIdPath, registry: RegistryDep) -> VehicleSummary:
    return registry.get(vehicle_id).summary()


@router.post(
    "/{vehicle_id}/commands",
    response_model=CommandResponse,
    openapi_extra=requires(Permission.COMMAND),
    responses={
        404: {"description": "Unknown vehicle"},
        409: {"description": "Vehicle not connected"},
        422: {"description": "Invalid parameters, or refused by safety rules (all listed)"},
        429: {"description": "Too many commands"},
        504: {"description": "The agent or flight controller did not answer in time"},
    },
)
async def send_command(
    vehicle_id: VehicleIdPath,
    command: Annotated[ClientCommand, Body()],
    request: Request,
    principal: CurrentPrincipal,
    commands: CommandServicesDep,
    budget: VehicleBudgetDep,
    override_reason: Annotated[
        str | None,
        Query(
            min_length=10,
            max_length=500,
            description="Admins only: send despite safety rules, for this stated reason (audited)",
        ),
    ] = None,
) -> CommandResponse:
    """Send a command and return the flight controller's answer.

    The command is checked against the safety rails first; a refusal lists every
    violated rule. ``set_mode`` to the mission mode (ArduPilot AUTO, PX4 MISSION) also
    runs the mission check on the mission on board (downloaded first): a mission that
    fails it, or none, is refused (422) unless an admin gives ``override_reason``.
    ``mission_set_current`` beyond the mission is refused at once (422). A refusal by the
    flight controller is an answer (status ``refused``, with its reason), so it comes back
    as 200; a missing answer is 504.
    """
    budget.spend(principal)
    outcome = await execute_command(
        commands, principal, client_address(request), vehicle_id, command, override_reason
    )
    return CommandResponse(vehicle_id=vehicle_id, command=command, outcome=outcome)


@router.get(
    "/{vehicle_id}/telemetry",
    response_model=TelemetryPage,
    openapi_extra=requires(Permission.READ),
)
async def telemetry_history(
    vehicle_id: VehicleIdPath,
    registry: RegistryDep,
    repository: RepositoryDep,
    start: Annotated[Moment | None, time_query("end - 10 min")] = None,
    end: Annotated[Moment | None, time_query("now")] = None,
    limit: Annotated[int, Query(ge=1, le=MAX_TELEMETRY_PAGE)] = 1000,
) -> TelemetryPage:
    """Stored telemetry samples in a time range, oldest first."""
    registry.get(vehicle_id)
    start_at, end_at = time_range(start, end, DEFAULT_HISTORY_S)
    rows = await asyncio.to_thread(repository.telemetry, vehicle_id, start_at, end_at, limit + 1)
    return TelemetryPage(
        vehicle_id=vehicle_id,
        start=start_at,
        end=end_at,
        limit=limit,
        samples=[TelemetrySample.model_validate(row) for row in rows[:limit]],
        truncated=len(rows) > limit,
    )
