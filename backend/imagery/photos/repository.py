"""Stored and refused survey photos: one row each, per (vehicle, photo id)."""

from __future__ import annotations

from dataclasses import dataclass

from sqlalchemy import ColumnElement, Engine, func, select
from sqlalchemy.exc import IntegrityError
from sqlalchemy.orm import Session

from backend.storage.models import PhotoRow


@dataclass(frozen=True)
class PhotoRecord:
    vehicle_id: str
    photo_id: str
    survey_id: str | None
    state: str  # "stored" or "refused"
    reason: str | None
    received_at: float
    path: str | None
    size: int
    meta_json: str | None


@dataclass(frozen=True)
class PhotoCount:
    vehicle_id: str
    state: str
    reason: str | None
    count: int


class PhotoRepository:
    def __init__(self, engine: Engine) -> None:
        self.engine = engine

    def add(self, record: PhotoRecord) -> bool:
        """Store the photo's row; False if that vehicle's photo id has one already."""
        try:
            with Session(self.engine) as session, session.begin():
                session.add(PhotoRow(**record.__dict__))
        except IntegrityError:
            return False
        return True

    def get(self, vehicle_id: str, photo_id: str) -> PhotoRecord | None:
        with Session(self.engine) as session:
            row = session.scalars(
                select(PhotoRow).where(
                    PhotoRow.vehicle_id == vehicle_id, PhotoRow.photo_id == photo_id
                )
            ).first()
            return None if row is None else _record(row)

    def of_survey(self, survey_id: str, state: str = "stored") -> list[PhotoRecord]:
        with Session(self.engine) as session:
            rows = session.scalars(
                select(PhotoRow)
                .where(PhotoRow.survey_id == survey_id, PhotoRow.state == state)
                .order_by(PhotoRow.vehicle_id, PhotoRow.photo_id)
            )
            return [_record(row) for row in rows]

    def of_vehicle(self, vehicle_id: str, limit: int) -> list[PhotoRecord]:
        """The vehicle's photos, stored and refused, newest first."""
        with Session(self.engine) as session:
            rows = session.scalars(
                select(PhotoRow)
                .where(PhotoRow.vehicle_id == vehicle_id)
                .order_by(PhotoRow.received_at.desc())
                .limit(limit)
            )
            return [_record(row) for row in rows]

    def vehicle_counts(self, vehicle_id: str) -> list[PhotoCount]:
        """One vehicle's photos by state and reason, whatever their survey."""
        return self._counts(PhotoRow.vehicle_id == vehicle_id)

    def counts(self, survey_id: str) -> list[PhotoCount]:
        """Photos per vehicle, state and reason, for one survey."""
        return self._counts(PhotoRow.survey_id == survey_id)

    def _counts(self, where: ColumnElement[bool]) -> list[PhotoCount]:
        with Session(self.engine) as session:
            rows = session.execute(
                select(PhotoRow.vehicle_id, PhotoRow.state, PhotoRow.reason, func.count())
                .where(where)
                .group_by(PhotoRow.vehicle_id, PhotoRow.state, PhotoRow.reason)
                .order_by(PhotoRow.vehicle_id)
            )
            return [PhotoCount(v, s, r, int(n)) for v, s, r, n in rows]

    def stored_bytes(self, vehicle_id: str) -> int:
        with Session(self.engine) as session:
            total = session.scalar(
                select(func.coalesce(func.sum(PhotoRow.size), 0)).where(
                    PhotoRow.vehicle_id == vehicle_id, PhotoRow.state == "stored"
                )
            )
            return int(total or 0)


def _record(row: PhotoRow) -> PhotoRecord:
    return PhotoRecord(
        row.vehicle_id,
        row.photo_id,
        row.survey_id,
        row.state,
        row.reason,
        row.received_at,
        row.path,
        row.size,
        row.meta_json,
    )
