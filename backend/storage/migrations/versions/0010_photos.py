"""Survey photos uploaded by the agents: stored or refused, with the reason

Revision ID: 0010_photos
Revises: 0009_surveys
Create Date: 2026-11-27 22:30:00
"""

from collections.abc import Sequence

import sqlalchemy as sa
from alembic import op

revision: str = "0010_photos"
down_revision: str | None = "0009_surveys"
branch_labels: str | Sequence[str] | None = None
depends_on: str | Sequence[str] | None = None


def upgrade() -> None:
    op.create_table(
        "photos",
        sa.Column(
            "id",
            sa.BigInteger().with_variant(sa.Integer(), "sqlite"),
            primary_key=True,
            autoincrement=True,
        ),
        sa.Column("vehicle_id", sa.String(length=64), nullable=False),
        sa.Column("photo_id", sa.String(length=80), nullable=False),
        sa.Column("survey_id", sa.String(length=80), nullable=True),
        sa.Column("state", sa.String(length=16), nullable=False),
        sa.Column("reason", sa.String(length=400), nullable=True),
        sa.Column("received_at", sa.Double(), nullable=False),
        sa.Column("path", sa.String(length=512), nullable=True),
        sa.Column("size", sa.BigInteger(), nullable=False),
        sa.Column("meta_json", sa.Text(), nullable=True),
        sa.UniqueConstraint("vehicle_id", "photo_id", name="uq_photos_vehicle_photo"),
    )
    op.create_index("ix_photos_survey", "photos", ["survey_id"])


def downgrade() -> None:
    op.drop_index("ix_photos_survey", table_name="photos")
    op.drop_table("photos")
