"""LIDAR scans: one row per turn, the binary frame kept whole

Revision ID: 0008_scans
Revises: 0007_audit_token
Create Date: 2026-11-25 06:00:00
"""

from collections.abc import Sequence

import sqlalchemy as sa
from alembic import op

revision: str = "0008_scans"
down_revision: str | None = "0007_audit_token"
branch_labels: str | Sequence[str] | None = None
depends_on: str | Sequence[str] | None = None


def upgrade() -> None:
    op.create_table(
        "scans",
        sa.Column(
            "id",
            sa.BigInteger().with_variant(sa.Integer(), "sqlite"),
            primary_key=True,
            autoincrement=True,
        ),
        sa.Column("vehicle_id", sa.String(length=64), sa.ForeignKey("vehicles.id"), nullable=False),
        sa.Column("stream_id", sa.String(length=64), nullable=False),
        sa.Column("seq", sa.BigInteger(), nullable=False),
        sa.Column("time", sa.Double(), nullable=False),
        sa.Column("beams", sa.Integer(), nullable=False),
        sa.Column("frame", sa.LargeBinary(), nullable=False),
        sa.UniqueConstraint("vehicle_id", "seq", "time", name="uq_scan"),
    )
    op.create_index("ix_scans_vehicle_time", "scans", ["vehicle_id", "time"])
    op.create_index("ix_scans_time", "scans", ["time"])


def downgrade() -> None:
    op.drop_index("ix_scans_time", table_name="scans")
    op.drop_index("ix_scans_vehicle_time", table_name="scans")
    op.drop_table("scans")
