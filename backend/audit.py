"""The audit log: who did what, when, from where, and how it ended. Append-only."""

from __future__ import annotations

import json
import logging
import time
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

from sqlalchemy import Engine, insert, select
from sqlalchemy.orm import Session

from backend.storage.models import AuditRow
from backend.storage.spool import RowSpool

log = logging.getLogger(__name__)

DETAIL_LIMIT = 2000


@dataclass(frozen=True)
class AuditEntry:
    actor: str
    role: str
    source: str
    action: str
    target: str
    outcome: str  # ok, refused, failed, denied
    detail: dict[str, Any]


@dataclass(frozen=True)
class AuditQuery:
    actor: str | None = None
    action: str | None = None
    target: str | None = None
    since: float | None = None
    until: float | None = None
    before_id: int | None = None  # paging: entries older than this id
    limit: int = 100


FIELD_LIMIT = 300


def _clipped(value: Any) -> Any:
    """Long strings (an agent's refusal text, say) shortened so the entry stays readable."""
    if isinstance(value, str):
        return value if len(value) <= FIELD_LIMIT else value[:FIELD_LIMIT] + "…"
    if isinstance(value, dict):
        return {key: _clipped(item) for key, item in value.items()}
    if isinstance(value, list | tuple):
        return [_clipped(item) for item in value]
    return value


class AuditLog:
    def __init__(self, engine: Engine, spool: RowSpool | None = None) -> None:
        self.engine = engine
        # Where rows wait while the database is unavailable (none: the error propagates).
        self.spool = spool

    def record(self, entry: AuditEntry) -> None:
        detail = json.dumps(_clipped(entry.detail), default=str, sort_keys=True)
        if len(detail) > DETAIL_LIMIT:
            # Still valid JSON, whatever a peer put in it.
            detail = json.dumps({"truncated": detail[: DETAIL_LIMIT - 100]})
        values = {
            "time": time.time(),
            "actor": entry.actor[:80],
            "role": entry.role,
            "source": entry.source[:64],
            "action": entry.action,
            "target": entry.target[:128],
            "outcome": entry.outcome,
            "detail": detail,
        }
        if self.spool is not None:
            self.spool.write(AuditRow.__tablename__, values)
        else:
            with self.engine.begin() as connection:
                connection.execute(insert(AuditRow).values(**values))
        log.info("audit: %s %s %s -> %s", entry.actor, entry.action, entry.target, entry.outcome)

    def query(self, query: AuditQuery) -> Sequence[AuditRow]:
        statement = select(AuditRow).order_by(AuditRow.id.desc()).limit(query.limit)
        if query.actor is not None:
            statement = statement.where(AuditRow.actor == query.actor)
        if query.action is not None:
            statement = statement.where(AuditRow.action == query.action)
        if query.target is not None:
            statement = statement.where(AuditRow.target == query.target)
        if query.since is not None:
            statement = statement.where(AuditRow.time >= query.since)
        if query.until is not None:
            statement = statement.where(AuditRow.time <= query.until)
        if query.before_id is not None:
            statement = statement.where(AuditRow.id < query.before_id)
        with Session(self.engine) as session:
            return session.scalars(statement).all()
