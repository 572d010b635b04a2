"""sequence gaps still open, kept across hub restarts

Revision ID: 0006_sequence_gaps
Revises: 0005_event_mission_item
Create Date: 2026-11-25 04:30:00
"""

from collections.abc import Sequence

import sqlalchemy as sa
from alembic import op

revision: str = "0006_sequence_gaps"
down_revision: str | None = "0005_event_mission_item"
branch_labels: str | Sequence[str] | None = None
depends_on: str | Sequence[str] | None = None


def upgrade() -> None:
    op.create_table(
        "sequence_gaps",
        sa.Column("vehicle_id", sa.String(length=64), nullable=False),
        sa.Column("stream_id", sa.String(length=64), nullable=False),
        sa.Column("kind", sa.String(length=16), nullable=False),
        sa.Column("first_seq", sa.BigInteger(), nullable=False),
        sa.Column("last_seq", sa.BigInteger(), nullable=False),
        sa.PrimaryKeyConstraint("vehicle_id", "stream_id", "kind", "first_seq"),
    )


def downgrade() -> None:
    op.drop_table("sequence_gaps")
