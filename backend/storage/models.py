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


class UserRow(Base):
    __tablename__ = "users"

    id: Mapped[int] = mapped_column(RowId, primary_key=True, autoincrement=True)
    username: Mapped[str] = mapped_column(String(64), unique=True)
    password_hash: Mapped[str] = mapped_column(String(255))
    role: Mapped[str] = mapped_column(String(16))
    disabled: Mapped[bool] = mapped_column(Boolean, default=False)
    created_at: Mapped[float] = mapped_column(Double)


class UserTokenRow(Base):
    """Bearer credentials of users: dashboard sessions, OAuth2 access tokens, API tokens.

    Only a SHA-256 of each token is stored: tokens are 256-bit random, so a slow KDF
    adds nothing, and lookups by hash stay one index probe per request."""

    __tablename__ = "user_tokens"

    id: Mapped[int] = mapped_column(RowId, primary_key=True, autoincrement=True)
    user_id: Mapped[int] = mapped_column(ForeignKey("users.id"), index=True)
    kind: Mapped[str] = mapped_column(String(16), doc="session, access or api")
    name: Mapped[str] = mapped_column(String(128), default="")
    token_hash: Mapped[str] = mapped_column(String(64), unique=True)
    scopes: Mapped[str] = mapped_column(String(128), doc="comma-separated permissions")
    created_at: Mapped[float] = mapped_column(Double)
    expires_at: Mapped[float | None] = mapped_column(Double)
    revoked_at: Mapped[float | None] = mapped_column(Double)


class AgentTokenRow(Base):
    """A vehicle's enrolment: its agent's token, hashed. One vehicle may have several
    (rotation), each revocable on its own."""

    __tablename__ = "agent_tokens"

    id: Mapped[int] = mapped_column(RowId, primary_key=True, autoincrement=True)
    vehicle_id: Mapped[str] = mapped_column(String(64), index=True)
    token_hash: Mapped[str] = mapped_column(String(64), unique=True)
    created_at: Mapped[float] = mapped_column(Double)
    created_by: Mapped[str] = mapped_column(String(64))
    revoked_at: Mapped[float | None] = mapped_column(Double)


class AuditRow(Base):
    """Append-only: the migration adds triggers that refuse UPDATE and DELETE."""

    __tablename__ = "audit_log"
    __table_args__ = (Index("ix_audit_time", "time"), Index("ix_audit_actor_time", "actor", "time"))

    id: Mapped[int] = mapped_column(RowId, primary_key=True, autoincrement=True)
    time: Mapped[float] = mapped_column(Double)
    actor: Mapped[str] = mapped_column(String(80))
    role: Mapped[str] = mapped_column(String(16))
    source: Mapped[str] = mapped_column(String(64), doc="client address")
    action: Mapped[str] = mapped_column(String(48))
    target: Mapped[str] = mapped_column(String(128), default="")
    outcome: Mapped[str] = mapped_column(String(16), doc="ok, refused, failed or denied")
    detail: Mapped[str] = mapped_column(String(2000), default="")


class SafetyRailsRow(Base):
    """Safety rails for the site (scope 'site') or one vehicle (scope 'vehicle:<id>')."""

    __tablename__ = "safety_rails"

    scope: Mapped[str] = mapped_column(String(80), primary_key=True)
    rails_json: Mapped[str] = mapped_column(String(100_000))
    updated_at: Mapped[float] = mapped_column(Double)
    updated_by: Mapped[str] = mapped_column(String(64))
