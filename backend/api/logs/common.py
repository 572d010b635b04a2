"""Limits and paging that the flight log's routes share."""

from __future__ import annotations

import time
from typing import Annotated, Any, Literal

from fastapi import Path

from backend.storage.models import FlightRow

MAX_PAGE = 1000
MAX_POINTS = 10_000
MAX_ID = 2**62  # ids are 64-bit in the database
Metric = Literal["alt_rel", "alt_msl", "groundspeed", "battery_remaining", "climb_rate"]
FlightIdPath = Annotated[int, Path(ge=1, le=MAX_ID)]


def next_before_id(rows: list[Any], limit: int) -> int | None:
    """The cursor of the next page: the last row's id when this page is full."""
    return int(rows[-1].id) if len(rows) == limit else None


def flight_end(flight: FlightRow) -> float:
    """When a flight ended, or now while it goes on."""
    return flight.end_time if flight.end_time is not None else time.time()
