"""A flight exported as CSV, GeoJSON or a MAVLink .tlog, streamed."""

from __future__ import annotations

import asyncio
import itertools
import logging
from collections.abc import Iterator
from typing import Any, Literal

from fastapi.responses import StreamingResponse

from backend.api.deps import LogbookDep, RegistryDep
from backend.api.logs.common import MAX_PAGE, FlightIdPath, flight_end
from backend.api.security import SecuredRouter, requires
from backend.auth.policy import Permission
from backend.errors import Conflict, GcsError
from backend.exports import (
    ExportEvent,
    ExportFlight,
    ExportSample,
    csv_chunks,
    geojson_chunks,
    tlog_chunks,
)
from backend.fleet.registry import FleetRegistry
from backend.storage.logbook import Logbook
from backend.storage.models import FlightRow

router = SecuredRouter(tags=["flight log"])
log = logging.getLogger(__name__)


def _export_parts(
    registry: FleetRegistry, logbook: Logbook, flight: FlightRow
) -> tuple[ExportFlight, Iterator[ExportSample], Iterator[ExportEvent]]:
    record = registry.get(flight.vehicle_id)
    end = flight_end(flight)
    export_flight = ExportFlight(
        id=flight.id,
        vehicle_id=flight.vehicle_id,
        autopilot=record.autopilot,
        vehicle_type=record.vehicle_type,
        system_id=record.system_id,
        start_time=flight.start_time,
        end_time=flight.end_time,
    )
    samples = (
        ExportSample(**row)
        for row in logbook.iter_series(flight.vehicle_id, flight.start_time, end)
    )
    events = (
        ExportEvent(time=row.time, kind=row.kind, severity=row.severity, text=row.text)
        for row in reversed(
            logbook.events(flight.vehicle_id, None, flight.start_time, end, None, MAX_PAGE)
        )
    )
    return export_flight, samples, events


class ExportFailed(GcsError):
    """The export could not be written (500, saying why): an answer, never an empty file."""


def _not_empty(samples: Iterator[ExportSample], flight: FlightRow) -> Iterator[ExportSample]:
    """``samples`` as they were; Conflict (409) for a flight with none stored (its
    telemetry pruned, say), whose export would be an empty file."""
    first = next(samples, None)
    if first is None:
        raise Conflict(f"flight {flight.id} has no telemetry stored to export")
    return itertools.chain([first], samples)


def _started(chunks: Iterator[Any], flight: FlightRow, format: str) -> Iterator[Any]:
    """``chunks`` with the first already written, so that an exporter that fails on the
    flight's first samples is a 500 saying so, not a 200 with an empty file. (A failure
    further on, once the answer has started, cuts the download short: a broken download
    the client sees, never a complete-looking one.)"""
    try:
        first = next(chunks, None)
    except Exception as error:
        log.exception("flight %d's %s export failed", flight.id, format)
        raise ExportFailed(
            f"flight {flight.id}'s .{format} could not be written: {error!r}"
        ) from error
    if first is None:
        raise ExportFailed(f"flight {flight.id}'s .{format} export wrote nothing")
    return itertools.chain([first], chunks)


EXPORT_TYPES = {
    "csv": "text/csv",
    "geojson": "application/geo+json",
    "tlog": "application/octet-stream",
}


@router.get(
    "/flights/{flight_id}/export.{format}",
    openapi_extra=requires(Permission.READ),
    response_class=StreamingResponse,
    responses={200: {"content": {media: {} for media in EXPORT_TYPES.values()}}},
)
async def export_flight(
    flight_id: FlightIdPath,
    format: Literal["csv", "geojson", "tlog"],
    registry: RegistryDep,
    logbook: LogbookDep,
) -> StreamingResponse:
    """A flight as CSV, GeoJSON or a MAVLink .tlog (pymavlink, QGroundControl, MAVProxy),
    streamed from the database cursor; nothing is buffered whole."""
    flight = await asyncio.to_thread(logbook.flight, flight_id)
    export, samples, events = await asyncio.to_thread(_export_parts, registry, logbook, flight)
    samples = await asyncio.to_thread(_not_empty, samples, flight)
    chunks: Iterator[str] | Iterator[bytes]
    if format == "csv":
        chunks = csv_chunks(samples)
    elif format == "geojson":
        chunks = geojson_chunks(export, samples, events)
    else:
        chunks = tlog_chunks(export, samples, events)
    chunks = await asyncio.to_thread(_started, chunks, flight, format)
    filename = f"{flight.vehicle_id}_flight{flight.id}.{format}"
    return StreamingResponse(
        chunks,  # a sync iterator: Starlette runs it in a worker thread
        media_type=EXPORT_TYPES[format],
        headers={"Content-Disposition": f'attachment; filename="{filename}"'},
    )
