"""The stored schema. Times are Unix seconds (float) so SQLite and PostgreSQL agree."""

from __future__ import annotations

from sqlalchemy import (
    BigInteger,
    Boolean,
    Double,
    ForeignKey,
    Index,
    Integer,
    LargeBinary,
    SmallInteger,
    String,
    Text,
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
        Index("ix_telemetry_time", "time"),  # fleet-wide ranges and retention
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


# A sample's delivery identity and time. Every other column of TelemetryRow is a field of
# the vehicle's state, copied by name from the agent's snapshot (protocol's VehicleState).
TELEMETRY_KEY_COLUMNS = ("id", "vehicle_id", "stream_id", "seq", "time")
# The stored state fields, read off the model above so that a column added there is stored,
# read back, charted and exported with no second list to keep (the exporters' ExportSample
# and the API's Sample are typed mirrors, held to this by
# tests/unit/storage/test_telemetry_fields.py).
TELEMETRY_STATE_COLUMNS: tuple[str, ...] = tuple(
    column.name
    for column in TelemetryRow.__table__.columns
    if column.name not in TELEMETRY_KEY_COLUMNS
)


class ScanRow(Base):
    """One LIDAR turn, as the agent sent it (protocol/scans.py's binary frame): kept whole,
    so a replay or an export turns it into points exactly as the live path did."""

    __tablename__ = "scans"
    __table_args__ = (
        # (vehicle, seq, time): a scan sent twice (after a reconnect) is stored once. Not the
        # agent run's stream: a backlog kept on disk is replayed by the next run.
        UniqueConstraint("vehicle_id", "seq", "time", name="uq_scan"),
        Index("ix_scans_vehicle_time", "vehicle_id", "time"),
        Index("ix_scans_time", "time"),  # retention
    )

    id: Mapped[int] = mapped_column(RowId, primary_key=True, autoincrement=True)
    vehicle_id: Mapped[str] = mapped_column(String(64), ForeignKey("vehicles.id"))
    stream_id: Mapped[str] = mapped_column(String(64))
    seq: Mapped[int] = mapped_column(BigInteger)
    time: Mapped[float] = mapped_column(Double, doc="UTC of the first beam, Unix seconds")
    beams: Mapped[int] = mapped_column(Integer)
    frame: Mapped[bytes] = mapped_column(LargeBinary)


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
    # The credential used: session, access, api or agent (NULL: anonymous, the hub itself,
    # or an entry from before it was recorded), its id, and an API token's name.
    token_kind: Mapped[str | None] = mapped_column(String(16))
    token_id: Mapped[int | None] = mapped_column(BigInteger)
    token_name: Mapped[str | None] = mapped_column(String(128))


class SafetyRailsRow(Base):
    """Safety rails for the site (scope 'site') or one vehicle (scope 'vehicle:<id>')."""

    __tablename__ = "safety_rails"

    scope: Mapped[str] = mapped_column(String(80), primary_key=True)
    rails_json: Mapped[str] = mapped_column(String(100_000))
    updated_at: Mapped[float] = mapped_column(Double)
    updated_by: Mapped[str] = mapped_column(String(64))


class FlightRow(Base):
    """One flight: from arming to disarming, found in the telemetry as it is stored."""

    __tablename__ = "flights"
    __table_args__ = (
        # A flight is its vehicle's arming time: replayed telemetry finds the same flight.
        UniqueConstraint("vehicle_id", "start_time", name="uq_flight_start"),
        Index("ix_flights_vehicle_start", "vehicle_id", "start_time"),
    )

    id: Mapped[int] = mapped_column(RowId, primary_key=True, autoincrement=True)
    vehicle_id: Mapped[str] = mapped_column(String(64), ForeignKey("vehicles.id"))
    start_time: Mapped[float] = mapped_column(Double)
    end_time: Mapped[float | None] = mapped_column(Double, index=True)
    duration_s: Mapped[float | None] = mapped_column(Double)
    distance_m: Mapped[float | None] = mapped_column(Double)
    max_alt_m: Mapped[float | None] = mapped_column(Double)
    battery_used_pct: Mapped[float | None] = mapped_column(Double)
    samples: Mapped[int | None] = mapped_column(Integer)


class EventRow(Base):
    __tablename__ = "events"
    __table_args__ = (
        # Agent events are de-duplicated like telemetry; the hub's own have no seq.
        UniqueConstraint("vehicle_id", "stream_id", "seq", name="uq_event"),
        Index("ix_events_vehicle_time", "vehicle_id", "time"),
        Index("ix_events_time", "time"),
    )

    id: Mapped[int] = mapped_column(RowId, primary_key=True, autoincrement=True)
    vehicle_id: Mapped[str] = mapped_column(String(64), ForeignKey("vehicles.id"))
    stream_id: Mapped[str] = mapped_column(String(64))
    seq: Mapped[int | None] = mapped_column(BigInteger)
    time: Mapped[float] = mapped_column(Double)
    kind: Mapped[str] = mapped_column(String(16))
    severity: Mapped[int | None] = mapped_column(SmallInteger)
    text: Mapped[str] = mapped_column(String(500))
    # The mission item a "mission" event is about (hub numbering), so a flight log can be
    # queried by item rather than by parsing the text.
    mission_item: Mapped[int | None] = mapped_column(Integer)
    # Where a "camera" event's photo was taken (CAMERA_FEEDBACK), so a survey's photos can
    # be read back after a hub restart.
    photo_index: Mapped[int | None] = mapped_column(BigInteger)
    photo_lat: Mapped[float | None] = mapped_column(Double)
    photo_lon: Mapped[float | None] = mapped_column(Double)
    photo_alt_rel: Mapped[float | None] = mapped_column(Double)


class SequenceGapRow(Base):
    """A range of an agent stream still asked for: neither stored nor reported lost.
    Kept so that a restarted hub goes on waiting for it (and records it if lost)."""

    __tablename__ = "sequence_gaps"

    vehicle_id: Mapped[str] = mapped_column(String(64), primary_key=True)
    stream_id: Mapped[str] = mapped_column(String(64), primary_key=True)
    kind: Mapped[str] = mapped_column(String(16), primary_key=True)
    first_seq: Mapped[int] = mapped_column(BigInteger, primary_key=True)
    last_seq: Mapped[int] = mapped_column(BigInteger)


class CommandRow(Base):
    __tablename__ = "commands"
    __table_args__ = (Index("ix_commands_vehicle_time", "vehicle_id", "time"),)

    id: Mapped[int] = mapped_column(RowId, primary_key=True, autoincrement=True)
    time: Mapped[float] = mapped_column(Double, index=True)
    vehicle_id: Mapped[str] = mapped_column(String(64))
    actor: Mapped[str] = mapped_column(String(80))
    name: Mapped[str] = mapped_column(String(32))
    command_json: Mapped[str] = mapped_column(String(2000))
    status: Mapped[str] = mapped_column(String(16), doc="accepted, refused, timeout, failed")
    result: Mapped[str | None] = mapped_column(String(48))
    message: Mapped[str] = mapped_column(String(1000))


class MissionRunRow(Base):
    """A mission flown by a vehicle. Written by mission upload and execution (the
    MAVLink mission protocol); the table is here so the schema is whole."""

    __tablename__ = "mission_runs"
    __table_args__ = (Index("ix_mission_runs_vehicle_start", "vehicle_id", "started_at"),)

    id: Mapped[int] = mapped_column(RowId, primary_key=True, autoincrement=True)
    vehicle_id: Mapped[str] = mapped_column(String(64), ForeignKey("vehicles.id"))
    flight_id: Mapped[int | None] = mapped_column(ForeignKey("flights.id"))
    kind: Mapped[str] = mapped_column(String(32), doc="survey, formation, waypoints")
    items: Mapped[int] = mapped_column(Integer)
    started_at: Mapped[float] = mapped_column(Double)
    ended_at: Mapped[float | None] = mapped_column(Double)
    status: Mapped[str] = mapped_column(String(16))


class TlogRow(Base):
    """A .tlog recorded on board and uploaded by the agent after landing."""

    __tablename__ = "tlogs"

    id: Mapped[int] = mapped_column(RowId, primary_key=True, autoincrement=True)
    vehicle_id: Mapped[str] = mapped_column(String(64), index=True)
    filename: Mapped[str] = mapped_column(String(128))
    path: Mapped[str] = mapped_column(String(512))
    size: Mapped[int] = mapped_column(BigInteger)
    uploaded_at: Mapped[float] = mapped_column(Double)


class SurveyRow(Base):
    """One area survey: its plan, its drones' missions and progress, as validated JSON
    (backend.survey.flight.run.SurveyRun), so a restarted hub carries on with it."""

    __tablename__ = "surveys"
    __table_args__ = (Index("ix_surveys_state", "state"),)

    id: Mapped[str] = mapped_column(String(32), primary_key=True)
    created: Mapped[float] = mapped_column(Double)
    updated: Mapped[float] = mapped_column(Double)
    state: Mapped[str] = mapped_column(String(24))
    created_by: Mapped[str] = mapped_column(String(64))
    # Text, not a bounded String: a large survey's photos run to megabytes.
    run_json: Mapped[str] = mapped_column(Text)


class FormationRow(Base):
    """One formation mission: who started it and with what (the request as JSON), who
    stopped it and why, and its followers' tracking figures per leg and per mission."""

    __tablename__ = "formations"
    __table_args__ = (Index("ix_formations_started", "started"),)

    id: Mapped[str] = mapped_column(String(64), primary_key=True)
    started: Mapped[float] = mapped_column(Double)
    started_by: Mapped[str] = mapped_column(String(64))
    leader_id: Mapped[str | None] = mapped_column(String(64))
    request_json: Mapped[str] = mapped_column(Text)
    stopped: Mapped[float | None] = mapped_column(Double)
    stopped_by: Mapped[str | None] = mapped_column(String(64))
    stop_reason: Mapped[str | None] = mapped_column(Text)
    tracking_json: Mapped[str | None] = mapped_column(Text)


class PhotoRow(Base):
    """A survey photo an agent uploaded: stored (its JPEG under the hub's photos folder)
    or refused, with the reason. One row per (vehicle, photo id): uploads are idempotent."""

    __tablename__ = "photos"
    __table_args__ = (
        UniqueConstraint("vehicle_id", "photo_id", name="uq_photos_vehicle_photo"),
        Index("ix_photos_survey", "survey_id"),
    )

    id: Mapped[int] = mapped_column(RowId, primary_key=True, autoincrement=True)
    vehicle_id: Mapped[str] = mapped_column(String(64))
    photo_id: Mapped[str] = mapped_column(String(80))
    survey_id: Mapped[str | None] = mapped_column(String(80), nullable=True)
    state: Mapped[str] = mapped_column(String(16))  # "stored" or "refused"
    reason: Mapped[str | None] = mapped_column(String(400), nullable=True)
    received_at: Mapped[float] = mapped_column(Double)
    path: Mapped[str | None] = mapped_column(String(512), nullable=True)
    size: Mapped[int] = mapped_column(BigInteger)
    # What the agent said of the photo (protocol.photos.PhotoMeta), as JSON; null when
    # the refusal came before it could be read.
    meta_json: Mapped[str | None] = mapped_column(Text, nullable=True)


class LeaseClaimRow(Base):
    """Who flies a vehicle by hand, for every hub to see (several hubs): a claim holds
    until ``expires_at`` unless its hub renews it, so a hub that dies releases its
    pilots' vehicles within seconds (backend/storage/claims.py)."""

    __tablename__ = "lease_claims"

    vehicle_id: Mapped[str] = mapped_column(String(64), primary_key=True)
    holder: Mapped[str] = mapped_column(String(64))
    hub_id: Mapped[str] = mapped_column(String(64))
    expires_at: Mapped[float] = mapped_column(Double)
