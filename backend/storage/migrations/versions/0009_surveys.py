"""Area surveys: one row per survey, its plan and progress kept as JSON; where a camera
event's photo was taken

Revision ID: 0009_surveys
Revises: 0008_scans
Create Date: 2026-11-26 10:00:00
"""

from collections.abc import Sequence

import sqlalchemy as sa
from alembic import op

revision: str = "0009_surveys"
down_revision: str | None = "0008_scans"
branch_labels: str | Sequence[str] | None = None
depends_on: str | Sequence[str] | None = None


def upgrade() -> None:
    op.create_table(
        "surveys",
        sa.Column("id", sa.String(length=32), primary_key=True),
        sa.Column("created", sa.Double(), nullable=False),
        sa.Column("updated", sa.Double(), nullable=False),
        sa.Column("state", sa.String(length=24), nullable=False),
        sa.Column("created_by", sa.String(length=64), nullable=False),
        sa.Column("run_json", sa.Text(), nullable=False),
    )
    op.create_index("ix_surveys_state", "surveys", ["state"])
    with op.batch_alter_table("events") as events:
        events.add_column(sa.Column("photo_index", sa.BigInteger(), nullable=True))
        events.add_column(sa.Column("photo_lat", sa.Double(), nullable=True))
        events.add_column(sa.Column("photo_lon", sa.Double(), nullable=True))
        events.add_column(sa.Column("photo_alt_rel", sa.Double(), nullable=True))


def downgrade() -> None:
    with op.batch_alter_table("events") as events:
        for column in ("photo_alt_rel", "photo_lon", "photo_lat", "photo_index"):
            events.drop_column(column)
    op.drop_index("ix_surveys_state", table_name="surveys")
    op.drop_table("surveys")
