"""Reads and writes of stored vehicles and telemetry. Synchronous: callers run these in
a worker thread (``asyncio.to_thread``) so the event loop never blocks on the database."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import asdict
from typing import Any

from sqlalchemy import Connection, Engine, delete, func, insert, select, update
from sqlalchemy.orm import Session

from backend.storage.database import dialect_insert, transaction
from backend.storage.models import (
    TELEMETRY_STATE_COLUMNS,
    EventRow,
    SequenceGapRow,
    TelemetryRow,
    VehicleRow,
)
from backend.storage.records import StoredEvent, TelemetryEnvelope
from protocol.messages import Hello


class Repository:
    def __init__(self, engine: Engine) -> None:
        self.engine = engine
        self._telemetry_sql: tuple[str, tuple[str, ...]] | None = None

    def upsert_vehicle(self, hello: Hello, now: float) -> None:
        values = {
            "autopilot": hello.autopilot,
            "vehicle_type": hello.vehicle_type,
            "system_id": hello.system_id,
            "modes": ",".join(hello.modes),
            "last_seen": now,
        }
        statement = dialect_insert(self.engine, VehicleRow).values(
            id=hello.vehicle_id, first_seen=now, **values
        )
        statement = statement.on_conflict_do_update(index_elements=["id"], set_=values)
        with self.engine.begin() as connection:
            connection.execute(statement)

    def set_modes(self, vehicle_id: str, modes: list[str]) -> None:
        with self.engine.begin() as connection:
            connection.execute(
                update(VehicleRow).where(VehicleRow.id == vehicle_id).values(modes=",".join(modes))
            )

    def vehicles(self) -> Sequence[VehicleRow]:
        with Session(self.engine) as session:
            return session.scalars(select(VehicleRow).order_by(VehicleRow.id)).all()

    def insert_telemetry(
        self, batch: Sequence[TelemetryEnvelope], connection: Connection | None = None
    ) -> None:
        """Store a batch; a sample stored before (same vehicle, stream, seq) is skipped.

        No RETURNING: on PostgreSQL it makes SQLAlchemy give up batching and costs 5x in
        throughput, and nothing downstream needs to know which rows were new."""
        if not batch:
            return
        statement = dialect_insert(self.engine, TelemetryRow).on_conflict_do_nothing(
            index_elements=["vehicle_id", "stream_id", "seq"]
        )
        with transaction(self.engine, connection) as active:
            if self.engine.dialect.name == "sqlite":
                # The driver's executemany with the statement compiled once: SQLAlchemy's
                # per-row parameter handling cost more than SQLite's insert itself, and
                # every column here is a plain number, string or bool that sqlite3 takes
                # as it is.
                sql, order = self._sqlite_telemetry_insert(statement)
                rows = [_telemetry_row(envelope) for envelope in batch]
                active.exec_driver_sql(sql, [tuple(row[key] for key in order) for row in rows])
            else:
                active.execute(statement, [_telemetry_row(envelope) for envelope in batch])

    def _sqlite_telemetry_insert(self, statement: Any) -> tuple[str, tuple[str, ...]]:
        if self._telemetry_sql is None:
            keys = [*TELEMETRY_STATE_COLUMNS, "vehicle_id", "stream_id", "seq", "time"]
            compiled = statement.compile(dialect=self.engine.dialect, column_keys=keys)
            self._telemetry_sql = (str(compiled), tuple(compiled.positiontup or ()))
        return self._telemetry_sql

    def telemetry(
        self, vehicle_id: str, start: float, end: float, limit: int
    ) -> Sequence[TelemetryRow]:
        query = (
            select(TelemetryRow)
            .where(
                TelemetryRow.vehicle_id == vehicle_id,
                TelemetryRow.time >= start,
                TelemetryRow.time <= end,
            )
            .order_by(TelemetryRow.time, TelemetryRow.id)
            .limit(limit)
        )
        with Session(self.engine) as session:
            return session.scalars(query).all()

    def insert_events(
        self, events: Sequence[StoredEvent], connection: Connection | None = None
    ) -> int:
        if not events:
            return 0
        statement = (
            dialect_insert(self.engine, EventRow)
            .on_conflict_do_nothing(index_elements=["vehicle_id", "stream_id", "seq"])
            .returning(EventRow.id)
        )
        with transaction(self.engine, connection) as active:
            return len(active.execute(statement, [event_values(e) for e in events]).all())

    def highest_seq(self, vehicle_id: str, stream_id: str, kind: str) -> int | None:
        """The highest sequence number stored for an agent stream, of telemetry or events."""
        row = TelemetryRow if kind == "telemetry" else EventRow
        query = select(func.max(row.seq)).where(
            row.vehicle_id == vehicle_id, row.stream_id == stream_id
        )
        with self.engine.connect() as connection:
            found = connection.scalar(query)
        return None if found is None else int(found)

    def open_gaps(self, vehicle_id: str, stream_id: str, kind: str) -> list[tuple[int, int]]:
        """The ranges of an agent stream still waited for when they were last stored."""
        query = (
            select(SequenceGapRow.first_seq, SequenceGapRow.last_seq)
            .where(
                SequenceGapRow.vehicle_id == vehicle_id,
                SequenceGapRow.stream_id == stream_id,
                SequenceGapRow.kind == kind,
            )
            .order_by(SequenceGapRow.first_seq)
        )
        with self.engine.connect() as connection:
            return [(int(first), int(last)) for first, last in connection.execute(query)]

    def open_gaps_of(self, vehicle_id: str) -> list[tuple[str, str, int, int]]:
        """The lowest open range of each of a vehicle's streams, as (stream, kind,
        first, last): what to ask a reconnecting agent for."""
        lowest = (
            select(
                SequenceGapRow.stream_id,
                SequenceGapRow.kind,
                func.min(SequenceGapRow.first_seq).label("first_seq"),
            )
            .where(SequenceGapRow.vehicle_id == vehicle_id)
            .group_by(SequenceGapRow.stream_id, SequenceGapRow.kind)
            .subquery()
        )
        query = select(
            SequenceGapRow.stream_id,
            SequenceGapRow.kind,
            SequenceGapRow.first_seq,
            SequenceGapRow.last_seq,
        ).join(
            lowest,
            (SequenceGapRow.stream_id == lowest.c.stream_id)
            & (SequenceGapRow.kind == lowest.c.kind)
            & (SequenceGapRow.first_seq == lowest.c.first_seq)
            & (SequenceGapRow.vehicle_id == vehicle_id),
        )
        with self.engine.connect() as connection:
            return [
                (str(stream), str(kind), int(first), int(last))
                for stream, kind, first, last in connection.execute(query)
            ]

    def replace_open_gaps(
        self,
        holes: dict[tuple[str, str, str], list[tuple[int, int]]],
        connection: Connection | None = None,
    ) -> None:
        """Each (vehicle, stream, kind)'s open ranges become exactly ``holes``; in the
        caller's transaction, so they change with the batch that changed them."""
        if not holes:
            return
        with transaction(self.engine, connection) as active:
            for (vehicle_id, stream_id, kind), ranges in holes.items():
                active.execute(
                    delete(SequenceGapRow).where(
                        SequenceGapRow.vehicle_id == vehicle_id,
                        SequenceGapRow.stream_id == stream_id,
                        SequenceGapRow.kind == kind,
                    )
                )
                if ranges:
                    active.execute(
                        insert(SequenceGapRow),
                        [
                            {
                                "vehicle_id": vehicle_id,
                                "stream_id": stream_id,
                                "kind": kind,
                                "first_seq": first,
                                "last_seq": last,
                            }
                            for first, last in ranges
                        ],
                    )

    def count_telemetry(self, vehicle_id: str | None = None) -> int:
        query = select(func.count()).select_from(TelemetryRow)
        if vehicle_id is not None:
            query = query.where(TelemetryRow.vehicle_id == vehicle_id)
        with Session(self.engine) as session:
            return int(session.scalar(query) or 0)


def _telemetry_row(envelope: TelemetryEnvelope) -> dict[str, Any]:
    state = envelope.telemetry.state
    row: dict[str, Any] = {name: getattr(state, name) for name in TELEMETRY_STATE_COLUMNS}
    row.update(
        vehicle_id=envelope.vehicle_id,
        stream_id=envelope.stream_id,
        seq=envelope.telemetry.seq,
        time=envelope.telemetry.time,
    )
    return row


def event_values(event: StoredEvent) -> dict[str, object]:
    """An event as its row's columns: a photo in its own four."""
    values: dict[str, object] = asdict(event)
    del values["photo"]
    photo = event.photo
    values["photo_index"] = None if photo is None else photo.index
    values["photo_lat"] = None if photo is None else photo.lat
    values["photo_lon"] = None if photo is None else photo.lon
    values["photo_alt_rel"] = None if photo is None else photo.alt_rel
    return values
