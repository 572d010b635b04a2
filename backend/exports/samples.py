"""What an export reads: a flight, its telemetry samples and its events.

The exporters take plain iterables of these so the hub can feed them straight from
a database cursor; nothing here knows about storage or HTTP.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from datetime import UTC, datetime


@dataclass(frozen=True, slots=True)
class ExportSample:
    """One telemetry sample. ``None`` means the vehicle had not reported the value."""

    time: float  # unix seconds
    lat: float | None
    lon: float | None
    alt_msl: float | None  # metres above mean sea level
    alt_rel: float | None  # metres above home
    heading_deg: float | None
    groundspeed: float | None  # m/s
    climb_rate: float | None  # m/s, up is positive
    battery_voltage: float | None  # V
    battery_remaining: float | None  # percent
    mode: str
    armed: bool
    gps_fix: int  # GPS_FIX_TYPE
    satellites: int | None


@dataclass(frozen=True)
class ExportFlight:
    id: int
    vehicle_id: str
    autopilot: str  # "ardupilot" | "px4" | "generic"
    vehicle_type: str  # "multirotor", "rover", "fixed_wing", ...
    system_id: int
    start_time: float  # unix seconds
    end_time: float | None


@dataclass(frozen=True)
class ExportEvent:
    time: float  # unix seconds
    kind: str
    severity: int | None  # MAV_SEVERITY, 0 (emergency) .. 7 (debug)
    text: str


def finite(value: float | None) -> float | None:
    """``value`` if it is a finite number, else None (NaN and infinities are unknowns)."""
    return value if value is not None and math.isfinite(value) else None


def sample_position(sample: ExportSample) -> tuple[float, float] | None:
    """``(lat, lon)`` if the sample has a usable position, else None.

    Every exporter uses this one definition. Besides missing and non-finite values it
    rejects out-of-range coordinates and exactly (0, 0): autopilots report that before
    they have a position (ArduPilot's GLOBAL_POSITION_INT without an EKF origin), and
    a track that starts in the Gulf of Guinea helps nobody.
    """
    lat, lon = finite(sample.lat), finite(sample.lon)
    if lat is None or lon is None:
        return None
    if not (-90.0 <= lat <= 90.0 and -180.0 <= lon <= 180.0) or (lat == 0.0 and lon == 0.0):
        return None
    return lat, lon


def iso_utc(unix_time: float) -> str:
    """ISO 8601 in UTC with millisecond precision, e.g. ``2024-05-01T12:00:00.250Z``."""
    moment = datetime.fromtimestamp(unix_time, UTC)
    return moment.isoformat(timespec="milliseconds").replace("+00:00", "Z")
