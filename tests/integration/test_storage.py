"""Storage on both databases: migrations, idempotent batches, time-range reads."""

from __future__ import annotations

from dataclasses import replace

import pytest
from alembic.autogenerate import compare_metadata
from alembic.migration import MigrationContext
from sqlalchemy import Engine, text
from sqlalchemy.exc import DBAPIError

from backend.audit import AuditEntry, AuditLog, AuditQuery
from backend.formation.store import FormationRepository, StoredFormation
from backend.storage.database import migrate
from backend.storage.models import Base
from backend.storage.records import TelemetryEnvelope
from backend.storage.repository import Repository
from protocol.messages import Telemetry, VehicleState
from tests.support.hellos import agent_hello


def _sample(vehicle_id: str, seq: int, time: float) -> TelemetryEnvelope:
    state = VehicleState(alt_rel=float(seq), mode="GUIDED", armed=True, gps_fix=3)
    return TelemetryEnvelope(vehicle_id, "s", Telemetry(seq=seq, time=time, state=state))


def test_migrations_match_the_models(engine: Engine) -> None:
    migrate(engine)
    with engine.connect() as connection:
        differences = compare_metadata(MigrationContext.configure(connection), Base.metadata)
    assert differences == []
    migrate(engine)  # a second start is a no-op


def test_batches_are_idempotent_and_ranges_ordered(engine: Engine) -> None:
    migrate(engine)
    repository = Repository(engine)
    repository.upsert_vehicle(agent_hello("v1"), now=100.0)
    repository.upsert_vehicle(agent_hello("v1"), now=200.0)  # a reconnect updates, not duplicates
    assert [row.last_seen for row in repository.vehicles()] == [200.0]

    batch = [_sample("v1", seq, 1000.0 + seq) for seq in range(50)]
    repository.insert_telemetry(batch)
    assert repository.count_telemetry("v1") == 50
    # Resending an overlapping batch (a replay after reconnect) stores only what is new.
    repository.insert_telemetry([*batch[40:], _sample("v1", 50, 1050.0)])
    assert repository.count_telemetry("v1") == 51

    rows = repository.telemetry("v1", start=1010.0, end=1019.0, limit=100)
    assert [row.seq for row in rows] == list(range(10, 20))
    assert rows[0].alt_rel == 10.0
    assert rows[0].mode == "GUIDED"
    assert repository.telemetry("v1", start=1000.0, end=2000.0, limit=5)[-1].seq == 4


def test_audit_log_is_append_only(engine: Engine) -> None:
    migrate(engine)
    audit = AuditLog(engine)
    audit.record(AuditEntry("alice", "operator", "10.0.0.1", "command", "v1", "ok", {"n": 1}))
    for statement in ("UPDATE audit_log SET actor = 'mallory'", "DELETE FROM audit_log"):
        with pytest.raises(DBAPIError, match="append-only"), engine.begin() as connection:
            connection.execute(text(statement))
    (entry,) = audit.query(AuditQuery())
    assert (entry.actor, entry.action, entry.outcome) == ("alice", "command", "ok")


def test_a_formation_is_stored_when_started_and_again_when_stopped(engine: Engine) -> None:
    migrate(engine)
    formations = FormationRepository(engine)
    started = StoredFormation("formation-1a2b", 100.0, "olivia", "sim_1", '{"speed_ms": 1.5}')
    formations.save(started)
    formations.save(replace(started, id="formation-3c4d", started=200.0, leader_id=None))
    stopped = replace(
        started,
        stopped=160.0,
        stopped_by="admin",
        stop_reason="stopped by the operator",
        tracking_json='{"sim_2": {"mission": {"rms_xy_m": 0.4}}}',
    )
    formations.save(stopped)  # the same row, overwritten
    assert formations.get("formation-1a2b") == stopped
    assert [f.id for f in formations.recent(10)] == ["formation-3c4d", "formation-1a2b"]
    assert formations.get("formation-none") is None
