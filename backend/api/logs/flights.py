"""Flights (arm to disarm): their summaries and their telemetry."""

from __future__ import annotations

import asyncio
from typing import Annotated

from fastapi import Query
from pydantic import BaseModel, ConfigDict

from backend.api.deps import LogbookDep, RegistryDep
from backend.api.logs.common import (
    MAX_ID,
    MAX_PAGE,
    MAX_POINTS,
    FlightIdPath,
    Metric,
    flight_end,
    next_before_id,
)
from backend.api.schemas import Sample
from backend.api.security import SecuredRouter, requires
from backend.auth.policy import Permission

router = SecuredRouter(tags=["flight log"])


class Flight(BaseModel):
    model_config = ConfigDict(from_attributes=True)

    id: int
    vehicle_id: str
    start_time: float
    end_time: float | None
    duration_s: float | None
    distance_m: float | None
    max_alt_m: float | None
    battery_used_pct: float | None
    samples: int | None


class FlightPage(BaseModel):
    flights: list[Flight]
    next_before_id: int | None


class FlightTelemetry(BaseModel):
    flight_id: int
    vehicle_id: str
    samples: list[Sample]


@router.get("/flights", response_model=FlightPage, openapi_extra=requires(Permission.READ))
async def list_flights(
    registry: RegistryDep,
    logbook: LogbookDep,
    vehicle_id: Annotated[str | None, Query(max_length=64)] = None,
    before_id: Annotated[int | None, Query(ge=1, le=MAX_ID)] = None,
    limit: Annotated[int, Query(ge=1, le=MAX_PAGE)] = 50,
) -> FlightPage:
    """Flights (arm to disarm) with their summaries, newest first."""
    if vehicle_id is not None:
        registry.get(vehicle_id)
    rows = list(await asyncio.to_thread(logbook.flights, vehicle_id, before_id, limit))
    return FlightPage(
        flights=[Flight.model_validate(row) for row in rows],
        next_before_id=next_before_id(rows, limit),
    )


@router.get("/flights/{flight_id}", response_model=Flight, openapi_extra=requires(Permission.READ))
async def get_flight(flight_id: FlightIdPath, logbook: LogbookDep) -> Flight:
    return Flight.model_validate(await asyncio.to_thread(logbook.flight, flight_id))


@router.get(
    "/flights/{flight_id}/telemetry",
    response_model=FlightTelemetry,
    openapi_extra=requires(Permission.READ),
)
async def flight_telemetry(
    flight_id: FlightIdPath,
    logbook: LogbookDep,
    points: Annotated[int, Query(ge=2, le=MAX_POINTS)] = 2000,
    metric: Metric = "alt_rel",
) -> FlightTelemetry:
    """A flight's telemetry for replay and charts, min/max-preserving downsampled."""
    flight = await asyncio.to_thread(logbook.flight, flight_id)
    rows = await asyncio.to_thread(
        logbook.series,
        flight.vehicle_id,
        flight.start_time,
        flight_end(flight),
        points,
        metric,
    )
    return FlightTelemetry(
        flight_id=flight.id, vehicle_id=flight.vehicle_id, samples=[Sample(**r) for r in rows]
    )
