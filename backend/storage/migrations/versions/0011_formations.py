"""Formation missions: who started and stopped each, its request, and its followers'
tracking figures

Revision ID: 0011_formations
Revises: 0010_photos
Create Date: 2026-11-27 23:00:00
"""

from collections.abc import Sequence

import sqlalchemy as sa
from alembic import op

revision: str = "0011_formations"
down_revision: str | None = "0010_photos"
branch_labels: str | Sequence[str] | None = None
depends_on: str | Sequence[str] | None = None


def upgrade() -> None:
    op.create_table(
        "formations",
        sa.Column("id", sa.String(length=64), primary_key=True),
        sa.Column("started", sa.Double(), nullable=False),
        sa.Column("started_by", sa.String(length=64), nullable=False),
        sa.Column("leader_id", sa.String(length=64), nullable=True),
        sa.Column("request_json", sa.Text(), nullable=False),
        sa.Column("stopped", sa.Double(), nullable=True),
        sa.Column("stopped_by", sa.String(length=64), nullable=True),
        sa.Column("stop_reason", sa.Text(), nullable=True),
        sa.Column("tracking_json", sa.Text(), nullable=True),
    )
    op.create_index("ix_formations_started", "formations", ["started"])


def downgrade() -> None:
    op.drop_index("ix_formations_started", table_name="formations")
    op.drop_table("formations")
