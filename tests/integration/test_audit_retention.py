"""The audit log is pruned by the retention policy (365 days by default), while the
database still refuses to change any entry or delete one younger than 30 days."""

from __future__ import annotations

import time
from pathlib import Path

import pytest
from pydantic import ValidationError
from sqlalchemy import Engine, func, insert, select, text
from sqlalchemy.exc import DBAPIError

from backend.settings import HubSettings
from backend.storage.database import make_engine, migrate
from backend.storage.logbook import Logbook
from backend.storage.models import AuditRow
from backend.storage.retention import RetentionPolicy
from tests.conftest import ADMIN_PASSWORD, hub_settings
from tests.support.api import access_token, api_client
from tests.support.hub_server import running_hub
from tests.support.waiting import poll_until

DAY = 86400.0


def _entries_aged(engine: Engine, *ages_days: float) -> None:
    now = time.time()
    with engine.begin() as connection:
        for age in ages_days:
            connection.execute(
                insert(AuditRow).values(
                    time=now - age * DAY,
                    actor="alice",
                    role="operator",
                    source="10.0.0.1",
                    action=f"aged-{age:g}",
                    target="v1",
                    outcome="ok",
                    detail="{}",
                )
            )


def _actions(engine: Engine) -> list[str]:
    with engine.connect() as connection:
        return sorted(connection.scalars(select(AuditRow.action)))


def test_retention_prunes_old_audit_entries_and_the_database_guards_recent_ones(
    engine: Engine,
) -> None:
    migrate(engine)
    _entries_aged(engine, 400, 100, 40, 1)
    removed = Logbook(engine).apply_retention(RetentionPolicy(audit_days=365), time.time())
    assert removed == {"audit": 1}
    assert _actions(engine) == ["aged-1", "aged-100", "aged-40"]

    # Whatever the policy says, the database keeps the last 30 days, and every entry
    # stays as written.
    for statement in ("DELETE FROM audit_log", "UPDATE audit_log SET actor = 'mallory'"):
        with pytest.raises(DBAPIError, match="append-only"), engine.begin() as connection:
            connection.execute(text(statement))
    cutoff = time.time() - 35 * DAY
    with engine.begin() as connection:
        connection.execute(text("DELETE FROM audit_log WHERE time < :t"), {"t": cutoff})
    assert _actions(engine) == ["aged-1"]


def test_the_audit_retention_has_a_floor_and_a_default(tmp_path: Path) -> None:
    assert HubSettings(data_dir=tmp_path).retention_audit_days == 365
    with pytest.raises(ValidationError, match="retention_audit_days"):
        HubSettings(data_dir=tmp_path, retention_audit_days=7)


def test_the_hub_prunes_the_audit_log_by_default(tmp_path: Path) -> None:
    engine = make_engine(f"sqlite:///{tmp_path}/gcs.sqlite3")
    migrate(engine)
    _entries_aged(engine, 500)
    with running_hub(hub_settings(tmp_path)) as hub:

        def old_entry_gone() -> bool:
            with engine.connect() as connection:
                query = select(func.count()).where(AuditRow.action == "aged-500")
                return connection.scalar(query) == 0

        poll_until(old_entry_gone, 10, "the hub's retention to remove the 500-day-old entry")
        with api_client(hub, access_token(hub, "admin", ADMIN_PASSWORD)) as api:
            assert api.get("/api/v1/audit").status_code == 200
    engine.dispose()
