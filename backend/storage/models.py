"""The stored schema. Times are Unix seconds (float) so SQLite and PostgreSQL agree."""

from __future__ import annotations

from sqlalchemy import (
    BigInteger,
    Boolean,
    Double,
    ForeignKey,
    Index,
    Integer,
    SmallInteger,
    String,
    UniqueConstraint,
)
from sqlalchemy.orm import DeclarativeBase, Mapped, mapped_column

# SQLite only auto-increments a column declared exactly INTEGER PRIMARY KEY.
RowId = BigInteger().with_variant(Integer(), "sqlite")


class Base(DeclarativeBase):
    pass


class VehicleRow(Base):
    __tablename__ = "vehicles"

    id: Mapped[str] = mapped_column(String(64), primary_key=True)
    autopilot: Mapped[str] = mapped_column(String(32))
    vehicle_type: Mapped[str] = mapped_column(String(32))
    system_id: Mapped[int] = mapped_column(SmallInteger)
    modes: Mapped[str] = mapped_column(String(1024), default="", doc="comma-separated")
    first_seen: Mapped[float] = mapped_column(Double)
    last_seen: Mapped[float] = mapped_column(Double)


class TelemetryRow(Base):
    __tablename__ = "telemetry"
    __table_args__ = (
        # (vehicle, stream, seq) is the delivery identity: a resent sample is a duplicate.
        UniqueConstraint("vehicle_id", "stream_id", "seq", name="uq_telemetry_sample"),
        Index("ix_telemetry_vehicle_time", "vehicle_id", "time"),
    )

    id: Mapped[int] = mapped_column(RowId, primary_key=True, autoincrement=True)
    vehicle_id: Mapped[str] = mapped_column(String(64), ForeignKey("vehicles.id"))
    stream_id: Mapped[str] = mapped_column(String(64))
    seq: Mapped[int] = mapped_column(BigInteger)
    time: Mapped[float] = mapped_column(Double)
    mode: Mapped[str] = mapped_column(String(32))
    armed: Mapped[bool] = mapped_column(Boolean)
    lat: Mapped[float | None] = mapped_column(Double)
    lon: Mapped[float | None] = mapped_column(Double)
    alt_msl: Mapped[float | None] = mapped_column(Double)
    alt_rel: Mapped[float | None] = mapped_column(Double)
    heading_deg: Mapped[float | None] = mapped_column(Double)
    groundspeed: Mapped[float | None] = mapped_column(Double)
    climb_rate: Mapped[float | None] = mapped_column(Double)
    battery_voltage: Mapped[float | None] = mapped_column(Double)
    battery_remaining: Mapped[float | None] = mapped_column(Double)
    gps_fix: Mapped[int] = mapped_column(SmallInteger)
    satellites: Mapped[int | None] = mapped_column(SmallInteger)


# The state fields copied from a telemetry snapshot into a row, in one place.
TELEMETRY_STATE_COLUMNS = (
    "mode",
    "armed",
    "lat",
    "lon",
    "alt_msl",
    "alt_rel",
    "heading_deg",
    "groundspeed",
    "climb_rate",
    "battery_voltage",
    "battery_remaining",
    "gps_fix",
    "satellites",
)
