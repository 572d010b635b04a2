"""audit retention: the database lets entries older than 30 days be deleted

Revision ID: 0004_audit_retention
Revises: 0003
Create Date: 2026-11-25 04:30:00.000000
"""

from collections.abc import Sequence

from alembic import op

revision: str = "0004_audit_retention"
down_revision: str | None = "0003"
branch_labels: str | Sequence[str] | None = None
depends_on: str | Sequence[str] | None = None

# Entries stay unchangeable for ever, and undeletable for their first 30 days: the hub's
# retention (GCS_RETENTION_AUDIT_DAYS, at least 30) removes older ones, and nothing, not
# a bug nor a stolen connection of the app's, can shorten the recent trail. The number
# is written out here, not imported, so this revision means the same whatever the code.
_MIN_AGE_S = 30 * 86400

_SQLITE_DELETE_GUARD = f"""CREATE TRIGGER audit_log_no_delete BEFORE DELETE ON audit_log
    WHEN OLD.time > CAST(strftime('%s', 'now') AS REAL) - {_MIN_AGE_S}
    BEGIN SELECT RAISE(ABORT, 'the audit log is append-only for 30 days'); END"""
_SQLITE_OLD_DELETE_GUARD = """CREATE TRIGGER audit_log_no_delete BEFORE DELETE ON audit_log
    BEGIN SELECT RAISE(ABORT, 'the audit log is append-only'); END"""

_POSTGRES_GUARD = f"""CREATE OR REPLACE FUNCTION audit_log_append_only() RETURNS trigger AS $$
    BEGIN
        IF TG_OP = 'DELETE' AND OLD.time < extract(epoch from now()) - {_MIN_AGE_S} THEN
            RETURN OLD;
        END IF;
        RAISE EXCEPTION 'the audit log is append-only for 30 days';
    END $$ LANGUAGE plpgsql"""
_POSTGRES_OLD_GUARD = """CREATE OR REPLACE FUNCTION audit_log_append_only() RETURNS trigger AS $$
    BEGIN RAISE EXCEPTION 'the audit log is append-only'; END $$ LANGUAGE plpgsql"""


def upgrade() -> None:
    if op.get_bind().dialect.name == "postgresql":
        op.execute(_POSTGRES_GUARD)
        return
    op.execute("DROP TRIGGER audit_log_no_delete")
    op.execute(_SQLITE_DELETE_GUARD)


def downgrade() -> None:
    if op.get_bind().dialect.name == "postgresql":
        op.execute(_POSTGRES_OLD_GUARD)
        return
    op.execute("DROP TRIGGER audit_log_no_delete")
    op.execute(_SQLITE_OLD_DELETE_GUARD)
