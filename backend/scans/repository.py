"""Stored scans: batches in, time ranges out. Synchronous, run in a worker thread."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import asdict, dataclass

from sqlalchemy import Engine, select
from sqlalchemy.orm import Session

from backend.storage.database import dialect_insert
from backend.storage.models import ScanRow


@dataclass(frozen=True, slots=True)
class StoredScan:
    vehicle_id: str
    stream_id: str
    seq: int
    time: float
    beams: int
    frame: bytes


class ScanRepository:
    def __init__(self, engine: Engine) -> None:
        self.engine = engine

    def insert(self, batch: Sequence[StoredScan]) -> None:
        """Store a batch; a scan stored before (same vehicle, seq and time) is skipped."""
        if not batch:
            return
        statement = dialect_insert(self.engine, ScanRow).on_conflict_do_nothing(
            index_elements=["vehicle_id", "seq", "time"]
        )
        with self.engine.begin() as connection:
            connection.execute(statement, [asdict(scan) for scan in batch])

    def between(self, vehicle_id: str, start: float, end: float, limit: int) -> Sequence[ScanRow]:
        """Scans of one vehicle in [start, end], oldest first."""
        query = (
            select(ScanRow)
            .where(ScanRow.vehicle_id == vehicle_id, ScanRow.time >= start, ScanRow.time <= end)
            .order_by(ScanRow.time, ScanRow.id)
            .limit(limit)
        )
        with Session(self.engine) as session:
            return session.scalars(query).all()

    def latest(self, vehicle_id: str) -> ScanRow | None:
        query = (
            select(ScanRow)
            .where(ScanRow.vehicle_id == vehicle_id)
            .order_by(ScanRow.time.desc())
            .limit(1)
        )
        with Session(self.engine) as session:
            return session.scalars(query).first()
