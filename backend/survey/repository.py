"""Stored surveys: each one's plan and progress as JSON, written whole on each change
(a survey changes a few times a second at most; the hub batches its saves)."""

from __future__ import annotations

import time
from dataclasses import dataclass

from sqlalchemy import Engine, select
from sqlalchemy.orm import Session

from backend.storage.models import EventRow, SurveyRow


@dataclass(frozen=True)
class StoredSurvey:
    id: str
    created: float
    state: str
    created_by: str
    run_json: str


class SurveyRepository:
    def __init__(self, engine: Engine) -> None:
        self.engine = engine

    def save(self, survey: StoredSurvey) -> None:
        with Session(self.engine) as session, session.begin():
            row = session.get(SurveyRow, survey.id)
            if row is None:
                session.add(
                    SurveyRow(
                        id=survey.id,
                        created=survey.created,
                        updated=time.time(),
                        state=survey.state,
                        created_by=survey.created_by,
                        run_json=survey.run_json,
                    )
                )
            else:
                row.updated = time.time()
                row.state = survey.state
                row.run_json = survey.run_json

    def get(self, survey_id: str) -> StoredSurvey | None:
        with Session(self.engine) as session:
            row = session.get(SurveyRow, survey_id)
            return None if row is None else _stored(row)

    def in_states(self, states: list[str]) -> list[StoredSurvey]:
        with Session(self.engine) as session:
            rows = session.scalars(
                select(SurveyRow).where(SurveyRow.state.in_(states)).order_by(SurveyRow.created)
            )
            return [_stored(row) for row in rows]

    def photos(self, vehicle_ids: list[str], since: float) -> list[StoredPhoto]:
        return stored_photos(self.engine, vehicle_ids, since)

    def recent(self, limit: int) -> list[StoredSurvey]:
        with Session(self.engine) as session:
            rows = session.scalars(
                select(SurveyRow).order_by(SurveyRow.created.desc()).limit(limit)
            )
            return [_stored(row) for row in rows]


def _stored(row: SurveyRow) -> StoredSurvey:
    return StoredSurvey(row.id, row.created, row.state, row.created_by, row.run_json)


@dataclass(frozen=True)
class StoredPhoto:
    vehicle_id: str
    index: int
    lat: float
    lon: float
    alt_rel: float
    time: float


def stored_photos(engine: Engine, vehicle_ids: list[str], since: float) -> list[StoredPhoto]:
    """The photos the vehicles reported since a time, from the flight log, oldest first."""
    query = (
        select(
            EventRow.vehicle_id,
            EventRow.photo_index,
            EventRow.photo_lat,
            EventRow.photo_lon,
            EventRow.photo_alt_rel,
            EventRow.time,
        )
        .where(
            EventRow.vehicle_id.in_(vehicle_ids),
            EventRow.kind == "camera",
            EventRow.time >= since,
            EventRow.photo_lat.is_not(None),
        )
        .order_by(EventRow.time)
    )
    with engine.connect() as connection:
        return [
            StoredPhoto(
                vid, int(index or 0), float(lat or 0.0), float(lon or 0.0), float(alt or 0.0), at
            )
            for vid, index, lat, lon, alt, at in connection.execute(query)
        ]
