"""Time ranges from query parameters (Unix seconds or ISO 8601), checked once for all routes.

Both bounds are inclusive. Unix seconds are compared exactly as given, so a sample's own
``time`` (as the API returns it) finds that sample. An ISO 8601 date-time names a
microsecond, while a stored time is finer than that, so a date-time bound reaches one
microsecond further out: a date-time printed from a sample's time, rounded or truncated,
still includes it.
"""

from __future__ import annotations

import time
from datetime import UTC, datetime
from typing import Annotated

from fastapi import Query
from pydantic import BeforeValidator, Field

from backend.errors import InvalidRequest
from protocol.messages import MAX_UNIX_TIME


def _not_a_number(value: object) -> object:
    """A number is Unix seconds; pydantic's date-time would take it too (and one over
    2e10 as milliseconds), which would let a number past the range in by another door."""
    if isinstance(value, str | int | float) and not isinstance(value, bool):
        try:
            float(value)
        except ValueError:
            return value
        raise ValueError(f"a number is Unix seconds, from 0 to {MAX_UNIX_TIME:.0f}")
    return value


UnixSeconds = Annotated[float, Field(ge=0, le=MAX_UNIX_TIME, allow_inf_nan=False)]
IsoDateTime = Annotated[datetime, BeforeValidator(_not_a_number)]
Moment = UnixSeconds | IsoDateTime
MICROSECOND = 1e-6
RANGE_RULES = (
    f"Unix seconds (0 to {MAX_UNIX_TIME:.0f}, fractions kept exactly) or an ISO 8601 "
    "date-time (no time zone means UTC, precise to the microsecond) in the same range. "
    "Both bounds are inclusive."
)


def time_query(default: str) -> object:
    """The ``Query`` of a ``start`` or ``end`` parameter, describing what it accepts."""
    return Query(description=f"{RANGE_RULES} Default: {default}.")


TimeQuery = Annotated[Moment | None, time_query("unbounded")]


def time_range(start: Moment | None, end: Moment | None, span_s: float) -> tuple[float, float]:
    """Unix seconds; ``end`` defaults to now and ``start`` to ``span_s`` before it."""
    end_at = _timestamp(end, "end", +MICROSECOND) if end is not None else time.time()
    start_at = _timestamp(start, "start", -MICROSECOND) if start is not None else end_at - span_s
    _in_order(start_at, end_at)
    return start_at, end_at


def optional_time_range(
    start: Moment | None, end: Moment | None
) -> tuple[float | None, float | None]:
    start_at = _timestamp(start, "start", -MICROSECOND) if start is not None else None
    end_at = _timestamp(end, "end", +MICROSECOND) if end is not None else None
    if start_at is not None and end_at is not None:
        _in_order(start_at, end_at)
    return start_at, end_at


def _in_order(start_at: float, end_at: float) -> None:
    if start_at > end_at:
        raise InvalidRequest(
            "start", f"start ({start_at:.6f}) is after end ({end_at:.6f})", "query"
        )


def _timestamp(moment: Moment, field: str, widen_s: float) -> float:
    """Unix seconds, within the range any stored sample can have (as the protocol allows)."""
    if not isinstance(moment, datetime):
        return moment  # exact: already checked against the range by its type
    aware = moment if moment.tzinfo else moment.replace(tzinfo=UTC)
    try:
        seconds = aware.timestamp()
    except (OverflowError, ValueError, OSError):
        seconds = -1.0
    if not 0 <= seconds <= MAX_UNIX_TIME:
        raise InvalidRequest(field, f"{field} {moment} is out of range", "query")
    return seconds + widen_s
