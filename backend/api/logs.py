"""The flight log: downsampled telemetry, flights, events, commands, exports and .tlogs."""

from __future__ import annotations

import asyncio
import json
import re
import time
from collections.abc import Iterator
from pathlib import Path as FilePath
from typing import Annotated, Any, BinaryIO, Literal

from fastapi import Path, Query, Request, status
from fastapi.responses import FileResponse, StreamingResponse
from pydantic import BaseModel, ConfigDict, Field, field_validator

from backend.api.deps import HubDep
from backend.api.schemas import Sample
from backend.api.security import SecuredRouter, requires
from backend.api.time_ranges import (
    Moment,
    TimeQuery,
    optional_time_range,
    time_query,
    time_range,
)
from backend.auth.policy import Permission
from backend.errors import InvalidRequest, QuotaExceeded
from backend.exports import (
    ExportEvent,
    ExportFlight,
    ExportSample,
    csv_chunks,
    geojson_chunks,
    tlog_chunks,
)
from backend.hub import Hub
from backend.storage.models import FlightRow
from backend.storage.tlog_check import InvalidTlog, TlogChecker
from protocol.messages import VehicleId

router = SecuredRouter(tags=["flight log"])

MAX_PAGE = 1000
MAX_POINTS = 10_000
# The series reads the whole range before downsampling it; a week at 10 Hz is 6 M rows.
MAX_SERIES_SPAN_S = 7 * 86400
MAX_ID = 2**62  # ids are 64-bit in the database
Metric = Literal["alt_rel", "alt_msl", "groundspeed", "battery_remaining", "climb_rate"]
SAFE_FILENAME = re.compile(r"[^A-Za-z0-9_.-]")


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


class Series(BaseModel):
    start: float
    end: float
    points: int
    metric: str
    series: dict[str, list[Sample]]


class EventRecord(BaseModel):
    model_config = ConfigDict(from_attributes=True)

    id: int
    vehicle_id: str
    time: float
    kind: str
    severity: int | None
    text: str
    mission_item: int | None = None


class EventPage(BaseModel):
    events: list[EventRecord]
    next_before_id: int | None


class CommandRecord(BaseModel):
    model_config = ConfigDict(from_attributes=True)

    id: int
    time: float
    vehicle_id: str
    actor: str
    name: str
    # Stored as JSON text; answered as the object it is, as in the audit log's detail.
    command: dict[str, Any] = Field(
        validation_alias="command_json", description='The command as sent, e.g. {"name": "land"}'
    )
    status: str
    result: str | None
    message: str

    @field_validator("command", mode="before")
    @classmethod
    def _parsed(cls, stored: object) -> object:
        if not isinstance(stored, str):
            return stored
        try:
            value = json.loads(stored)
        except json.JSONDecodeError:
            return {"unparsed": stored}  # cut short at the column's size
        return value if isinstance(value, dict) else {"value": value}


class CommandPage(BaseModel):
    commands: list[CommandRecord]
    next_before_id: int | None


class Tlog(BaseModel):
    model_config = ConfigDict(from_attributes=True)

    id: int
    vehicle_id: str
    filename: str
    size: int
    uploaded_at: float


class Metrics(BaseModel):
    telemetry_written: int
    events_written: int
    batches: int
    write_retries: int
    database_available: bool
    writer_backlog: int
    writer_capacity: int
    last_batch_s: float
    connected_agents: int


def _next(rows: list[Any], limit: int) -> int | None:
    return int(rows[-1].id) if len(rows) == limit else None


@router.get("/telemetry/series", response_model=Series, openapi_extra=requires(Permission.READ))
async def telemetry_series(
    hub: HubDep,
    vehicle_id: Annotated[list[str] | None, Query(description="repeat; all if unset")] = None,
    start: Annotated[Moment | None, time_query("end - 1 h")] = None,
    end: Annotated[Moment | None, time_query("now")] = None,
    points: Annotated[int, Query(ge=2, le=MAX_POINTS)] = 1000,
    metric: Metric = "alt_rel",
) -> Series:
    """Telemetry of one vehicle or the fleet over a range, at most ``points`` samples per
    vehicle, keeping the true minimum and maximum of ``metric`` (a chart shows the real
    extremes, not every n-th row)."""
    start_at, end_at = time_range(start, end, 3600)
    if end_at - start_at > MAX_SERIES_SPAN_S:
        raise InvalidRequest(
            "start",
            f"the range is over {MAX_SERIES_SPAN_S / 86400:.0f} days; ask for less",
            "query",
        )
    vehicles = list(dict.fromkeys(vehicle_id or [r.id for r in hub.registry.all()]))
    for requested in vehicles:
        hub.registry.get(requested)
    series = {}
    for vehicle in vehicles:
        rows = await asyncio.to_thread(
            hub.logbook.series, vehicle, start_at, end_at, points, metric
        )
        series[vehicle] = [Sample(**row) for row in rows]
    return Series(start=start_at, end=end_at, points=points, metric=metric, series=series)


@router.get("/flights", response_model=FlightPage, openapi_extra=requires(Permission.READ))
async def list_flights(
    hub: HubDep,
    vehicle_id: Annotated[str | None, Query(max_length=64)] = None,
    before_id: Annotated[int | None, Query(ge=1, le=MAX_ID)] = None,
    limit: Annotated[int, Query(ge=1, le=MAX_PAGE)] = 50,
) -> FlightPage:
    """Flights (arm to disarm) with their summaries, newest first."""
    if vehicle_id is not None:
        hub.registry.get(vehicle_id)
    rows = list(await asyncio.to_thread(hub.logbook.flights, vehicle_id, before_id, limit))
    return FlightPage(
        flights=[Flight.model_validate(row) for row in rows], next_before_id=_next(rows, limit)
    )


FlightIdPath = Annotated[int, Path(ge=1, le=MAX_ID)]


@router.get("/flights/{flight_id}", response_model=Flight, openapi_extra=requires(Permission.READ))
async def get_flight(flight_id: FlightIdPath, hub: HubDep) -> Flight:
    return Flight.model_validate(await asyncio.to_thread(hub.logbook.flight, flight_id))


def _flight_end(flight: FlightRow) -> float:
    return flight.end_time if flight.end_time is not None else time.time()


@router.get(
    "/flights/{flight_id}/telemetry",
    response_model=FlightTelemetry,
    openapi_extra=requires(Permission.READ),
)
async def flight_telemetry(
    flight_id: FlightIdPath,
    hub: HubDep,
    points: Annotated[int, Query(ge=2, le=MAX_POINTS)] = 2000,
    metric: Metric = "alt_rel",
) -> FlightTelemetry:
    """A flight's telemetry for replay and charts, min/max-preserving downsampled."""
    flight = await asyncio.to_thread(hub.logbook.flight, flight_id)
    rows = await asyncio.to_thread(
        hub.logbook.series,
        flight.vehicle_id,
        flight.start_time,
        _flight_end(flight),
        points,
        metric,
    )
    return FlightTelemetry(
        flight_id=flight.id, vehicle_id=flight.vehicle_id, samples=[Sample(**r) for r in rows]
    )


def _export_parts(
    hub: Hub, flight: FlightRow
) -> tuple[ExportFlight, Iterator[ExportSample], Iterator[ExportEvent]]:
    record = hub.registry.get(flight.vehicle_id)
    end = _flight_end(flight)
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
        for row in hub.logbook.iter_series(flight.vehicle_id, flight.start_time, end)
    )
    events = (
        ExportEvent(time=row.time, kind=row.kind, severity=row.severity, text=row.text)
        for row in reversed(
            hub.logbook.events(flight.vehicle_id, None, flight.start_time, end, None, MAX_PAGE)
        )
    )
    return export_flight, samples, events


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
    flight_id: FlightIdPath, format: Literal["csv", "geojson", "tlog"], hub: HubDep
) -> StreamingResponse:
    """A flight as CSV, GeoJSON or a MAVLink .tlog (pymavlink, QGroundControl, MAVProxy),
    streamed from the database cursor; nothing is buffered whole."""
    flight = await asyncio.to_thread(hub.logbook.flight, flight_id)
    export, samples, events = await asyncio.to_thread(_export_parts, hub, flight)
    chunks: Iterator[str] | Iterator[bytes]
    if format == "csv":
        chunks = csv_chunks(samples)
    elif format == "geojson":
        chunks = geojson_chunks(export, samples, events)
    else:
        chunks = tlog_chunks(export, samples, events)
    filename = f"{flight.vehicle_id}_flight{flight.id}.{format}"
    return StreamingResponse(
        chunks,  # a sync iterator: Starlette runs it in a worker thread
        media_type=EXPORT_TYPES[format],
        headers={"Content-Disposition": f'attachment; filename="{filename}"'},
    )


@router.get("/events", response_model=EventPage, openapi_extra=requires(Permission.READ))
async def list_events(
    hub: HubDep,
    vehicle_id: Annotated[str | None, Query(max_length=64)] = None,
    kind: Annotated[str | None, Query(max_length=16)] = None,
    start: TimeQuery = None,
    end: TimeQuery = None,
    before_id: Annotated[int | None, Query(ge=1, le=MAX_ID)] = None,
    limit: Annotated[int, Query(ge=1, le=MAX_PAGE)] = 100,
) -> EventPage:
    """STATUSTEXTs, mode changes, arming, failsafes and link changes, newest first."""
    if vehicle_id is not None:
        hub.registry.get(vehicle_id)
    start_at, end_at = optional_time_range(start, end)
    rows = list(
        await asyncio.to_thread(
            hub.logbook.events, vehicle_id, kind, start_at, end_at, before_id, limit
        )
    )
    return EventPage(
        events=[EventRecord.model_validate(row) for row in rows], next_before_id=_next(rows, limit)
    )


@router.get("/commands", response_model=CommandPage, openapi_extra=requires(Permission.READ))
async def list_commands(
    hub: HubDep,
    vehicle_id: Annotated[str | None, Query(max_length=64)] = None,
    actor: Annotated[str | None, Query(max_length=80)] = None,
    start: TimeQuery = None,
    end: TimeQuery = None,
    before_id: Annotated[int | None, Query(ge=1, le=MAX_ID)] = None,
    limit: Annotated[int, Query(ge=1, le=MAX_PAGE)] = 100,
) -> CommandPage:
    """Commands sent, who sent them and what the vehicle answered, newest first."""
    if vehicle_id is not None:
        hub.registry.get(vehicle_id)
    start_at, end_at = optional_time_range(start, end)
    rows = list(
        await asyncio.to_thread(
            hub.logbook.commands, vehicle_id, actor, start_at, end_at, before_id, limit
        )
    )
    return CommandPage(
        commands=[CommandRecord.model_validate(row) for row in rows],
        next_before_id=_next(rows, limit),
    )


@router.post(
    "/vehicles/{vehicle_id}/tlogs",
    response_model=Tlog,
    status_code=status.HTTP_201_CREATED,
    openapi_extra=requires(Permission.AGENT),
)
async def upload_tlog(
    vehicle_id: Annotated[VehicleId, Path()],
    request: Request,
    hub: HubDep,
) -> Tlog:
    """An agent uploads the .tlog it recorded on board (body: the raw file).

    The body must be a .tlog (timestamped MAVLink frames: 422 otherwise, at the first
    record that is not), and fit the vehicle's quota (``max_tlog_bytes_per_vehicle``
    over all its files: 413 otherwise; ``max_tlog_bytes`` bounds one file)."""
    hub.registry.get(vehicle_id)
    quota = hub.settings.max_tlog_bytes_per_vehicle
    stored = sum(row.size for row in await asyncio.to_thread(hub.logbook.tlogs, vehicle_id))
    if stored >= quota:
        raise QuotaExceeded(_quota_used(vehicle_id, stored, quota))
    name = SAFE_FILENAME.sub("_", request.headers.get("x-filename", "flight.tlog"))[:100]
    folder = hub.settings.data_dir / "tlogs" / vehicle_id
    await asyncio.to_thread(folder.mkdir, parents=True, exist_ok=True)
    target = folder / f"{time.time_ns()}_{name}"
    size = 0
    checker = TlogChecker()
    try:
        with target.open("xb") as file:  # streamed to disk chunk by chunk
            async for chunk in request.stream():
                size += len(chunk)
                if stored + size > quota:
                    raise QuotaExceeded(_quota_used(vehicle_id, stored, quota))
                await asyncio.to_thread(_check_and_write, checker, file, chunk)
        checker.finish()
    except InvalidTlog as error:
        target.unlink(missing_ok=True)
        raise InvalidRequest("body", str(error)) from None
    except BaseException:
        target.unlink(missing_ok=True)  # no half files from a cut upload
        raise
    tlog_id = await asyncio.to_thread(hub.logbook.add_tlog, vehicle_id, name, str(target), size)
    return Tlog.model_validate(await asyncio.to_thread(hub.logbook.tlog, tlog_id))


def _check_and_write(checker: TlogChecker, file: BinaryIO, chunk: bytes) -> None:
    checker.feed(chunk)  # before the write: nothing that is not a .tlog is kept
    file.write(chunk)


def _quota_used(vehicle_id: str, stored: int, quota: int) -> str:
    return (
        f"this upload would take {vehicle_id}'s stored .tlogs over their quota of "
        f"{quota} bytes ({stored} bytes stored); ask an admin to remove old ones"
    )


@router.get(
    "/vehicles/{vehicle_id}/tlogs",
    response_model=list[Tlog],
    openapi_extra=requires(Permission.READ),
)
async def list_tlogs(vehicle_id: Annotated[VehicleId, Path()], hub: HubDep) -> list[Tlog]:
    hub.registry.get(vehicle_id)
    return [
        Tlog.model_validate(row) for row in await asyncio.to_thread(hub.logbook.tlogs, vehicle_id)
    ]


@router.get(
    "/tlogs/{tlog_id}",
    response_class=FileResponse,
    openapi_extra=requires(Permission.READ),
    responses={200: {"content": {"application/octet-stream": {}}}},
)
async def download_tlog(
    tlog_id: Annotated[int, Path(ge=1, le=MAX_ID)], hub: HubDep
) -> FileResponse:
    row = await asyncio.to_thread(hub.logbook.tlog, tlog_id)
    return FileResponse(
        FilePath(row.path), filename=row.filename, media_type="application/octet-stream"
    )


@router.get("/metrics", response_model=Metrics, openapi_extra=requires(Permission.READ))
async def metrics(hub: HubDep) -> Metrics:
    """The storage path's health: backlog against capacity shows backpressure building."""
    stats = hub.writer.stats
    return Metrics(
        telemetry_written=stats.written,
        events_written=stats.events_written,
        batches=stats.batches,
        write_retries=stats.retries,
        database_available=stats.database_available,
        writer_backlog=hub.writer.backlog,
        writer_capacity=hub.writer.capacity,
        last_batch_s=stats.last_batch_s,
        connected_agents=len(hub.agent_sessions),
    )
