"""The flight log: flights, downsampled telemetry, events, commands and uploaded .tlogs.

Synchronous like the other repositories; the API calls it from worker threads. Reads
that feed exports stream rows from the database cursor instead of loading them.
"""

from __future__ import annotations

import json
import time
from collections.abc import Iterable, Iterator, Sequence
from typing import Any, TypeVar

from sqlalchemy import (
    Connection,
    Engine,
    Select,
    and_,
    delete,
    func,
    insert,
    or_,
    select,
    update,
)
from sqlalchemy.orm import InstrumentedAttribute, Session

from backend.errors import NotFound
from backend.storage.database import dialect_insert, transaction
from backend.storage.downsample import minmax_downsample
from backend.storage.models import (
    TELEMETRY_STATE_COLUMNS,
    AuditRow,
    CommandRow,
    EventRow,
    FlightRow,
    ScanRow,
    TelemetryRow,
    TlogRow,
)
from backend.storage.retention import RetentionPolicy
from common.geodesy import haversine_m

# The columns a chart, a replay or an export needs.
SERIES_COLUMNS = ("time", *TELEMETRY_STATE_COLUMNS)


_Logged = TypeVar("_Logged", EventRow, CommandRow)
_Kept = TypeVar("_Kept", FlightRow, TlogRow)


def _page(
    query: Select[_Logged],
    row: type[_Logged],
    start: float | None,
    end: float | None,
    before_id: int | None,
    equal: Iterable[tuple[InstrumentedAttribute[str], str | None]] = (),
) -> Select[_Logged]:
    """Rows in a time range (either end open), older than ``before_id`` when paging, and
    with each column of ``equal`` that is given a value at that value: the same window
    for the events and the commands."""
    for column, value in equal:
        if value is not None:
            query = query.where(column == value)
    if start is not None:
        query = query.where(row.time >= start)
    if end is not None:
        query = query.where(row.time <= end)
    if before_id is not None:
        query = query.where(row.id < before_id)
    return query


def _series_query(vehicle_id: str, start: float, end: float) -> Any:
    columns = [getattr(TelemetryRow, name) for name in SERIES_COLUMNS]
    return (
        select(*columns)
        .where(
            TelemetryRow.vehicle_id == vehicle_id,
            TelemetryRow.time >= start,
            TelemetryRow.time <= end,
        )
        .order_by(TelemetryRow.time, TelemetryRow.id)
    )


class Logbook:
    def __init__(self, engine: Engine) -> None:
        self.engine = engine

    # -- flights -----------------------------------------------------------

    def open_flights(self) -> dict[str, int]:
        """Flights still open (the hub stopped while they flew), by vehicle."""
        with Session(self.engine) as session:
            rows = session.execute(
                select(FlightRow.vehicle_id, FlightRow.id).where(FlightRow.end_time.is_(None))
            ).all()
        return {vehicle_id: flight_id for vehicle_id, flight_id in rows}

    def open_flight(
        self, vehicle_id: str, start_time: float, connection: Connection | None = None
    ) -> int:
        """The flight of ``vehicle_id`` armed at ``start_time``, created if it is new."""
        statement = (
            dialect_insert(self.engine, FlightRow)
            .values(vehicle_id=vehicle_id, start_time=start_time)
            .on_conflict_do_nothing(index_elements=["vehicle_id", "start_time"])
            .returning(FlightRow.id)
        )
        with transaction(self.engine, connection) as active:
            created = active.execute(statement).scalar()
            if created is not None:
                return int(created)
            return int(
                active.execute(
                    select(FlightRow.id).where(
                        FlightRow.vehicle_id == vehicle_id, FlightRow.start_time == start_time
                    )
                ).scalar_one()
            )

    def close_flight(
        self, flight_id: int, end_time: float, connection: Connection | None = None
    ) -> None:
        """End a flight and summarise it from its stored telemetry."""
        with transaction(self.engine, connection) as active:
            flight = active.execute(
                select(FlightRow.vehicle_id, FlightRow.start_time).where(FlightRow.id == flight_id)
            ).one()
            rows = active.execute(
                select(
                    TelemetryRow.lat,
                    TelemetryRow.lon,
                    TelemetryRow.alt_rel,
                    TelemetryRow.battery_remaining,
                )
                .where(
                    TelemetryRow.vehicle_id == flight.vehicle_id,
                    TelemetryRow.time >= flight.start_time,
                    TelemetryRow.time <= end_time,
                )
                .order_by(TelemetryRow.time, TelemetryRow.id)
            ).all()
            active.execute(
                update(FlightRow)
                .where(FlightRow.id == flight_id)
                .values(
                    end_time=end_time, duration_s=end_time - flight.start_time, **_summary(rows)
                )
            )

    def flights(
        self, vehicle_id: str | None, before_id: int | None, limit: int
    ) -> Sequence[FlightRow]:
        query = select(FlightRow).order_by(FlightRow.id.desc()).limit(limit)
        if vehicle_id is not None:
            query = query.where(FlightRow.vehicle_id == vehicle_id)
        if before_id is not None:
            query = query.where(FlightRow.id < before_id)
        with Session(self.engine) as session:
            return session.scalars(query).all()

    def flight(self, flight_id: int) -> FlightRow:
        return self._one(FlightRow, flight_id, "flight")

    def _one(self, row: type[_Kept], key: int, what: str) -> _Kept:
        """The row with this id, or NotFound naming it."""
        with Session(self.engine) as session:
            found = session.get(row, key)
        if found is None:
            raise NotFound(f"no {what} {key}")
        return found

    # -- telemetry series --------------------------------------------------

    def series(
        self, vehicle_id: str, start: float, end: float, points: int, metric: str
    ) -> list[dict[str, Any]]:
        """The samples in a range, at most ``points``, keeping the min and max of ``metric``."""
        with self.engine.connect() as connection:
            rows = connection.execute(_series_query(vehicle_id, start, end)).all()
        index = SERIES_COLUMNS.index(metric)
        kept = minmax_downsample(rows, points, lambda row: row[index])
        return [dict(zip(SERIES_COLUMNS, row, strict=True)) for row in kept]

    def iter_series(
        self, vehicle_id: str, start: float, end: float, page: int = 5000
    ) -> Iterator[dict[str, Any]]:
        """Every sample in a range, page by page (for exports).

        Keyset pages, each on a connection borrowed only for that page: a slow download
        must not hold a pooled connection the storage writer needs."""
        after: tuple[float, int] | None = None
        while True:
            query = _series_query(vehicle_id, start, end).add_columns(TelemetryRow.id)
            if after is not None:
                query = query.where(
                    or_(
                        TelemetryRow.time > after[0],
                        and_(TelemetryRow.time == after[0], TelemetryRow.id > after[1]),
                    )
                )
            with self.engine.connect() as connection:
                rows = connection.execute(query.limit(page)).all()
            for row in rows:
                yield dict(zip(SERIES_COLUMNS, row[:-1], strict=True))
            if len(rows) < page:
                return
            after = (rows[-1][0], rows[-1][-1])

    # -- events ------------------------------------------------------------

    def events(
        self,
        vehicle_id: str | None,
        kind: str | None,
        start: float | None,
        end: float | None,
        before_id: int | None,
        limit: int,
    ) -> Sequence[EventRow]:
        query = select(EventRow).order_by(EventRow.time.desc(), EventRow.id.desc()).limit(limit)
        equal = ((EventRow.vehicle_id, vehicle_id), (EventRow.kind, kind))
        query = _page(query, EventRow, start, end, before_id, equal)
        with Session(self.engine) as session:
            return session.scalars(query).all()

    # -- commands ----------------------------------------------------------

    def record_command(
        self,
        vehicle_id: str,
        actor: str,
        command: dict[str, Any],
        status: str,
        result: str | None,
        message: str,
    ) -> None:
        values = command_row(vehicle_id, actor, command, status, result, message)
        with self.engine.begin() as connection:
            connection.execute(insert(CommandRow).values(**values))

    def commands(
        self,
        vehicle_id: str | None,
        actor: str | None,
        start: float | None,
        end: float | None,
        before_id: int | None,
        limit: int,
    ) -> Sequence[CommandRow]:
        query = select(CommandRow).order_by(CommandRow.id.desc()).limit(limit)
        equal = ((CommandRow.vehicle_id, vehicle_id), (CommandRow.actor, actor))
        query = _page(query, CommandRow, start, end, before_id, equal)
        with Session(self.engine) as session:
            return session.scalars(query).all()

    # -- uploaded .tlogs ---------------------------------------------------

    def add_tlog(self, vehicle_id: str, filename: str, path: str, size: int) -> int:
        with self.engine.begin() as connection:
            result = connection.execute(
                insert(TlogRow)
                .values(
                    vehicle_id=vehicle_id,
                    filename=filename,
                    path=path,
                    size=size,
                    uploaded_at=time.time(),
                )
                .returning(TlogRow.id)
            )
            return int(result.scalar_one())

    def tlogs(self, vehicle_id: str) -> Sequence[TlogRow]:
        with Session(self.engine) as session:
            return session.scalars(
                select(TlogRow).where(TlogRow.vehicle_id == vehicle_id).order_by(TlogRow.id)
            ).all()

    def tlog(self, tlog_id: int) -> TlogRow:
        return self._one(TlogRow, tlog_id, "tlog")

    # -- retention ---------------------------------------------------------

    def apply_retention(self, policy: RetentionPolicy, now: float) -> dict[str, int]:
        """Delete rows older than the policy keeps; returns how many went, per table."""
        removed: dict[str, int] = {}
        targets: tuple[tuple[str, Any, Any, float | None], ...] = (
            ("telemetry", TelemetryRow, TelemetryRow.time, policy.telemetry_days),
            # Scans are the flight's sensor data: they go when its telemetry goes.
            ("scans", ScanRow, ScanRow.time, policy.telemetry_days),
            ("events", EventRow, EventRow.time, policy.events_days),
            ("commands", CommandRow, CommandRow.time, policy.commands_days),
            ("flights", FlightRow, FlightRow.end_time, policy.flights_days),
            # The database refuses to delete younger entries (AUDIT_MIN_RETENTION_DAYS).
            ("audit", AuditRow, AuditRow.time, policy.audit_days),
        )
        with self.engine.begin() as connection:
            for name, table, column, days in targets:
                if days is None:
                    continue
                result = connection.execute(delete(table).where(column < now - days * 86400))
                removed[name] = int(result.rowcount or 0)
        return removed

    def count(self, model: Any) -> int:
        with Session(self.engine) as session:
            return int(session.scalar(select(func.count()).select_from(model)) or 0)


def _summary(rows: Sequence[Any]) -> dict[str, Any]:
    distance = 0.0
    previous = None
    altitudes = [row.alt_rel for row in rows if row.alt_rel is not None]
    batteries = [row.battery_remaining for row in rows if row.battery_remaining is not None]
    for row in rows:
        if row.lat is None or row.lon is None:
            continue
        if previous is not None:
            distance += haversine_m(previous[0], previous[1], row.lat, row.lon)
        previous = (row.lat, row.lon)
    return {
        "distance_m": distance,
        "max_alt_m": max(altitudes) if altitudes else None,
        "battery_used_pct": batteries[0] - batteries[-1] if batteries else None,
        "samples": len(rows),
    }


def command_row(
    vehicle_id: str,
    actor: str,
    command: dict[str, Any],
    status: str,
    result: str | None,
    message: str,
) -> dict[str, Any]:
    """The command log's row for one command (written directly or through a spool)."""
    return {
        "time": time.time(),
        "vehicle_id": vehicle_id,
        "actor": actor,
        "name": str(command.get("name", "")),
        "command_json": json.dumps(command)[:2000],
        "status": status,
        "result": result,
        "message": message[:1000],
    }
