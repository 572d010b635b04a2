"""audit entries name the token used (its kind, id and, for an API token, its name)

Revision ID: 0007_audit_token
Revises: 0006_sequence_gaps
Create Date: 2026-11-25 05:00:00
"""

from collections.abc import Sequence

import sqlalchemy as sa
from alembic import op

revision: str = "0007_audit_token"
down_revision: str | None = "0006_sequence_gaps"
branch_labels: str | Sequence[str] | None = None
depends_on: str | Sequence[str] | None = None


def upgrade() -> None:
    # Added columns only: the append-only triggers refuse UPDATE and DELETE of rows, not a
    # new column, and earlier entries keep NULL (their token was not recorded).
    op.add_column("audit_log", sa.Column("token_kind", sa.String(length=16), nullable=True))
    op.add_column("audit_log", sa.Column("token_id", sa.BigInteger(), nullable=True))
    op.add_column("audit_log", sa.Column("token_name", sa.String(length=128), nullable=True))


def downgrade() -> None:
    # Plain DROP COLUMN (SQLite 3.35+): a batch copy of the table would lose its triggers.
    op.drop_column("audit_log", "token_name")
    op.drop_column("audit_log", "token_id")
    op.drop_column("audit_log", "token_kind")
