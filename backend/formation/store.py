"""Stored formation missions: a row per formation, written when it starts, when its shape
changes and when it stops (with its tracking figures then)."""

from __future__ import annotations

from dataclasses import dataclass

from sqlalchemy import Engine, select
from sqlalchemy.orm import Session

from backend.storage.models import FormationRow


@dataclass(frozen=True)
class StoredFormation:
    id: str
    started: float
    started_by: str
    leader_id: str | None
    request_json: str
    stopped: float | None = None
    stopped_by: str | None = None
    stop_reason: str | None = None
    tracking_json: str | None = None


class FormationRepository:
    def __init__(self, engine: Engine) -> None:
        self.engine = engine

    def save(self, formation: StoredFormation) -> None:
        """Insert, or overwrite the row of the same id."""
        with Session(self.engine) as session, session.begin():
            session.merge(
                FormationRow(
                    id=formation.id,
                    started=formation.started,
                    started_by=formation.started_by,
                    leader_id=formation.leader_id,
                    request_json=formation.request_json,
                    stopped=formation.stopped,
                    stopped_by=formation.stopped_by,
                    stop_reason=formation.stop_reason,
                    tracking_json=formation.tracking_json,
                )
            )

    def close_left_open(self, now: float, reason: str) -> list[str]:
        """Mark the formations a hub that died left running as stopped, for ``reason``;
        their ids. A formation lives in the hub's memory only: none resumes."""
        with Session(self.engine) as session, session.begin():
            rows = list(session.scalars(select(FormationRow).where(FormationRow.stopped.is_(None))))
            for row in rows:
                row.stopped, row.stop_reason = now, reason
            return [row.id for row in rows]

    def get(self, formation_id: str) -> StoredFormation | None:
        with Session(self.engine) as session:
            row = session.get(FormationRow, formation_id)
            return None if row is None else _stored(row)

    def recent(self, limit: int) -> list[StoredFormation]:
        with Session(self.engine) as session:
            rows = session.scalars(
                select(FormationRow).order_by(FormationRow.started.desc()).limit(limit)
            )
            return [_stored(row) for row in rows]


def _stored(row: FormationRow) -> StoredFormation:
    return StoredFormation(
        row.id,
        row.started,
        row.started_by,
        row.leader_id,
        row.request_json,
        row.stopped,
        row.stopped_by,
        row.stop_reason,
        row.tracking_json,
    )
