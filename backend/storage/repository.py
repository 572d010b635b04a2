"""Reads and writes of stored vehicles and telemetry. Synchronous: callers run these in
a worker thread (``asyncio.to_thread``) so the event loop never blocks on the database."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

from sqlalchemy import Engine, func, select
from sqlalchemy.dialects import postgresql, sqlite
from sqlalchemy.orm import Session

from backend.storage.models import TELEMETRY_STATE_COLUMNS, TelemetryRow, VehicleRow
from gcs.protocol import Hello, Telemetry


@dataclass(frozen=True)
class TelemetryEnvelope:
    """A telemetry message with the identity the hub knows it under."""

    vehicle_id: str
    stream_id: str
    telemetry: Telemetry


def _insert(engine: Engine, table: Any) -> Any:
    """An INSERT that skips rows already stored, in the engine's own dialect."""
    if engine.dialect.name == "postgresql":
        return postgresql.insert(table)
    return sqlite.insert(table)


class Repository:
    def __init__(self, engine: Engine) -> None:
        self.engine = engine

    def upsert_vehicle(self, hello: Hello, now: float) -> None:
        values = {
            "autopilot": hello.autopilot,
            "vehicle_type": hello.vehicle_type,
            "system_id": hello.system_id,
            "modes": ",".join(hello.modes),
            "last_seen": now,
        }
        statement = _insert(self.engine, VehicleRow).values(
            id=hello.vehicle_id, first_seen=now, **values
        )
        statement = statement.on_conflict_do_update(index_elements=["id"], set_=values)
        with self.engine.begin() as connection:
            connection.execute(statement)

    def vehicles(self) -> Sequence[VehicleRow]:
        with Session(self.engine) as session:
            return session.scalars(select(VehicleRow).order_by(VehicleRow.id)).all()

    def insert_telemetry(self, batch: Sequence[TelemetryEnvelope]) -> int:
        """Store a batch; samples stored before are skipped. Returns rows written."""
        if not batch:
            return 0
        rows = [_telemetry_row(envelope) for envelope in batch]
        statement = (
            _insert(self.engine, TelemetryRow)
            .on_conflict_do_nothing(index_elements=["vehicle_id", "stream_id", "seq"])
            # rowcount is unreliable for batched inserts; the returned ids are not.
            .returning(TelemetryRow.id)
        )
        with self.engine.begin() as connection:
            return len(connection.execute(statement, rows).all())

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
