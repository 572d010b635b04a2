"""Time ranges from query parameters (ISO 8601 or Unix seconds), checked once for all routes."""

from __future__ import annotations

import time
from datetime import UTC, datetime

from backend.errors import InvalidRequest
from gcs.protocol import MAX_UNIX_TIME


def time_range(start: datetime | None, end: datetime | None, span_s: float) -> tuple[float, float]:
    """Unix seconds; ``end`` defaults to now and ``start`` to ``span_s`` before it."""
    end_at = _timestamp(end, "end") if end else time.time()
    start_at = _timestamp(start, "start") if start else end_at - span_s
    _in_order(start_at, end_at)
    return start_at, end_at


def optional_time_range(
    start: datetime | None, end: datetime | None
) -> tuple[float | None, float | None]:
    start_at = _timestamp(start, "start") if start else None
    end_at = _timestamp(end, "end") if end else None
    if start_at is not None and end_at is not None:
        _in_order(start_at, end_at)
    return start_at, end_at


def _in_order(start_at: float, end_at: float) -> None:
    if start_at > end_at:
        raise InvalidRequest("start", f"start ({start_at:.3f}) is after end ({end_at:.3f})")


def _timestamp(moment: datetime, field: str) -> float:
    """Unix seconds, within the range any stored sample can have (as the protocol allows)."""
    aware = moment if moment.tzinfo else moment.replace(tzinfo=UTC)
    try:
        seconds = aware.timestamp()
    except (OverflowError, ValueError, OSError):
        seconds = -1.0
    if not 0 <= seconds <= MAX_UNIX_TIME:
        raise InvalidRequest(field, f"{field} {moment} is out of range")
    return seconds
