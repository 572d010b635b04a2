"""Telemetry of one vehicle or the fleet over a time range, downsampled for charts."""

from __future__ import annotations

import asyncio
from typing import Annotated

from fastapi import Query
from pydantic import BaseModel

from backend.api.deps import LogbookDep, RegistryDep
from backend.api.logs.common import MAX_POINTS, Metric
from backend.api.schemas import Sample
from backend.api.security import SecuredRouter, requires
from backend.api.time_ranges import Moment, time_query, time_range
from backend.auth.policy import Permission
from backend.errors import InvalidRequest

router = SecuredRouter(tags=["flight log"])

# The series reads the whole range before downsampling it; a week at 10 Hz is 6 M rows.
MAX_SERIES_SPAN_S = 7 * 86400


class Series(BaseModel):
    start: float
    end: float
    points: int
    metric: str
    series: dict[str, list[Sample]]


@router.get("/telemetry/series", response_model=Series, openapi_extra=requires(Permission.READ))
async def telemetry_series(
    registry: RegistryDep,
    logbook: LogbookDep,
    vehicle_id: Annotated[list[str] | None, Query(description="repeat; all if unset")] = None,
    start: Annotated[Moment | None, time_query("end - 1 h")] = None,
    end: Annotated[Moment | None, time_query("now")] = None,
    points: Annotated[int, Query(ge=2, le=MAX_POINTS)] = 1000,
    metric: Metric = "alt_rel",
) -> Series:
    """Telemetry of one vehicle or the fleet over a range, at most ``points`` samples per
    vehicle, keeping the true minimum and maximum of ``metric`` (a chart shows the real
    extremes, not every n-th row)."""
    start_at, end_at = time_range(start, end, 3600)
    if end_at - start_at > MAX_SERIES_SPAN_S:
        raise InvalidRequest(
            "start",
            f"the range is over {MAX_SERIES_SPAN_S / 86400:.0f} days; ask for less",
            "query",
        )
    vehicles = list(dict.fromkeys(vehicle_id or [r.id for r in registry.all()]))
    for requested in vehicles:
        registry.get(requested)
    series = {}
    for vehicle in vehicles:
        rows = await asyncio.to_thread(logbook.series, vehicle, start_at, end_at, points, metric)
        series[vehicle] = [Sample(**row) for row in rows]
    return Series(start=start_at, end=end_at, points=points, metric=metric, series=series)
