"""The audit log: who did what, when, from where, and how it ended. Append-only."""

from __future__ import annotations

import json
import logging
import time
from collections.abc import Sequence
from dataclasses import dataclass
from enum import StrEnum
from typing import Any

from sqlalchemy import Engine, insert, select
from sqlalchemy.orm import Session

from backend.auth.policy import Principal
from backend.storage.models import AuditRow
from backend.storage.spool import RowSpool

log = logging.getLogger(__name__)

DETAIL_LIMIT = 2000


class AuditAction(StrEnum):
    """Every action the audit log records (the OpenAPI document lists them as an enum)."""

    LOGIN = "login"  # a password login, ok or denied; target: the user name
    LOGOUT = "logout"
    TOKEN_CREATE = "token.create"  # an API token; target: its name
    TOKEN_REVOKE = "token.revoke"  # target: the token's id
    USER_CREATE = "user.create"
    USER_UPDATE = "user.update"  # role, disabled or password changed
    AGENT_TOKEN_CREATE = "agent_token.create"  # a vehicle enrolled; target: the vehicle
    AGENT_TOKEN_REVOKE = "agent_token.revoke"
    RAILS_UPDATE = "rails.update"  # safety rails; target: "site" or the vehicle
    RAILS_CLEAR = "rails.clear"
    COMMAND = "command"  # anything sent to a vehicle: commands, parameters, missions
    CONTROL_LEASE = "control.lease"  # manual control taken, given back or revoked; target: vehicle
    FORMATION_START = "formation.start"  # target: the formation's id (the leader's if refused)
    FORMATION_CHANGE = "formation.change"  # a new shape or spacing in flight
    FORMATION_STOP = "formation.stop"
    DENIED = "denied"  # a route refused for want of a permission; target: method and path


@dataclass(frozen=True)
class AuditEntry:
    actor: str
    role: str
    source: str
    action: AuditAction
    target: str
    outcome: str  # ok, refused, failed, denied
    detail: dict[str, Any]
    # The credential the actor used: session, access, api or agent; its id; an API
    # token's name. So a scoped integration's acts are told from its user's own.
    token_kind: str | None = None
    token_id: int | None = None
    token_name: str | None = None


def principal_audit_entry(
    principal: Principal,
    source: str,
    action: AuditAction,
    target: str,
    outcome: str,
    detail: dict[str, Any],
) -> AuditEntry:
    """An entry for what ``principal`` did, naming the token it used."""
    return AuditEntry(
        actor=principal.name,
        role=principal.role,
        source=source,
        action=action,
        target=target,
        outcome=outcome,
        detail=detail,
        token_kind=principal.token_kind or None,
        token_id=principal.token_id,
        token_name=principal.token_name or None,
    )


@dataclass(frozen=True)
class AuditQuery:
    actor: str | None = None
    action: AuditAction | None = None
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
            "token_kind": entry.token_kind,
            "token_id": entry.token_id,
            "token_name": entry.token_name[:128] if entry.token_name is not None else None,
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
