"""Stored safety rails: the site's, and per-vehicle overrides, as validated JSON."""

from __future__ import annotations

import time

from sqlalchemy import Engine, delete, select
from sqlalchemy.orm import Session

from backend.storage.models import SafetyRailsRow

SITE = "site"


def vehicle_scope(vehicle_id: str) -> str:
    return f"vehicle:{vehicle_id}"


class RailsRepository:
    def __init__(self, engine: Engine) -> None:
        self.engine = engine

    def get(self, scope: str) -> str | None:
        with Session(self.engine) as session:
            return session.scalar(
                select(SafetyRailsRow.rails_json).where(SafetyRailsRow.scope == scope)
            )

    def put(self, scope: str, rails_json: str, updated_by: str) -> None:
        with Session(self.engine) as session, session.begin():
            row = session.get(SafetyRailsRow, scope)
            if row is None:
                session.add(
                    SafetyRailsRow(
                        scope=scope,
                        rails_json=rails_json,
                        updated_at=time.time(),
                        updated_by=updated_by,
                    )
                )
            else:
                row.rails_json = rails_json
                row.updated_at = time.time()
                row.updated_by = updated_by

    def delete(self, scope: str) -> bool:
        with self.engine.begin() as connection:
            result = connection.execute(delete(SafetyRailsRow).where(SafetyRailsRow.scope == scope))
        return bool(result.rowcount)
