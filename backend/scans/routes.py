"""LIDAR scans: the latest, by time range, the site's point map and its obstacles. The
routes reach the scan service and what they read beside it through the typed
dependencies of ``deps.py``."""

from __future__ import annotations

import asyncio
import math
from typing import Annotated, Literal

from fastapi import Query
from fastapi.responses import Response
from pydantic import BaseModel, Field

from backend.api.deps import LogbookDep, RegistryDep
from backend.api.logs.common import FlightIdPath, flight_end
from backend.api.security import SecuredRouter, requires
from backend.api.time_ranges import Moment, time_query, time_range
from backend.api.vehicles import VehicleIdPath
from backend.auth.policy import Permission
from backend.errors import NotFound
from backend.scans.deps import RefreshObstaclesDep, ScansDep
from backend.scans.export import ply_bytes
from backend.scans.pointmap import PointMap
from backend.scans.points import WorldPoints, world_points
from backend.scans.service import ScanService
from backend.scans.views import obstacle_views, point_map_view, site_origin
from backend.storage.logbook import Logbook
from common.geodesy import LocalFrame
from protocol.messages import MAX_MAP_POINTS, Obstacle, PointMapView, SiteOrigin
from protocol.scans import decode_scan

router = SecuredRouter(tags=["scans"])

MAX_SCANS_PAGE = 100
DEFAULT_SCAN_HISTORY_S = 60.0


class ScanPoints(BaseModel):
    """One scan's returns in the world."""

    vehicle_id: str
    seq: int
    time: float = Field(description="UTC of the first beam, Unix seconds")
    duration_s: float
    beams: int
    replayed: bool
    enu: list[tuple[float, float, float]] = Field(
        description="east, north, up metres from the site origin, one per return"
    )
    geodetic: list[tuple[float, float, float]] = Field(
        description="latitude, longitude (degrees), altitude (m) of the same points"
    )


class ScanPage(BaseModel):
    vehicle_id: str
    start: float
    end: float
    limit: int
    site: SiteOrigin | None = Field(description="the origin of the points' east/north/up")
    scans: list[ScanPoints]
    truncated: bool


class ScanDiagnosticsBody(BaseModel):
    vehicle_id: str
    received: int
    live: int
    replayed: int
    stored: int
    cleaned_ranges: int = Field(description="ranges beyond the sensor's maximum, dropped")
    rejected: dict[str, int] = Field(description="refused scans by reason")
    source: str | None = Field(
        default=None, description="the agent's scan source: its LIDAR model, mavlink or ros2"
    )
    source_counts: dict[str, int] = Field(
        default_factory=dict,
        description="the agent's parser, since the agent started: packets, points, and "
        "what it dropped by reason (dropped_bad_checksum, dropped_noise_bytes, ...)",
    )


def _body(scans: ScanService, vehicle_id: str, data: bytes) -> ScanPoints:
    frame = decode_scan(data)
    site = scans.site_for(frame)
    points: WorldPoints = world_points(frame, site)
    return ScanPoints(
        vehicle_id=vehicle_id,
        seq=frame.seq,
        time=frame.utc_time,
        duration_s=frame.duration_s,
        beams=frame.beams,
        replayed=frame.replayed,
        enu=[tuple(p) for p in points.enu.round(3).tolist()],
        geodetic=[tuple(p) for p in points.geodetic(site).round(8).tolist()],
    )


@router.get(
    "/vehicles/{vehicle_id}/scans/latest",
    response_model=ScanPoints,
    openapi_extra=requires(Permission.READ),
    responses={404: {"description": "Unknown vehicle, or no scan from it yet"}},
)
async def latest_scan(vehicle_id: VehicleIdPath, scans: ScansDep, fleet: RegistryDep) -> ScanPoints:
    """The vehicle's newest scan as world points (live, else the newest stored)."""
    fleet.get(vehicle_id)
    row = await asyncio.to_thread(scans.repository.latest, vehicle_id)
    latest = scans.latest.get(vehicle_id)
    if latest is None and row is None:
        raise NotFound(f"no scan from {vehicle_id!r} yet")
    if latest is not None and (row is None or latest.frame.utc_time >= row.time):
        frame = latest.frame
        site = scans.site_for(frame)
        return ScanPoints(
            vehicle_id=vehicle_id,
            seq=frame.seq,
            time=frame.utc_time,
            duration_s=frame.duration_s,
            beams=frame.beams,
            replayed=frame.replayed,
            enu=[tuple(p) for p in latest.points.enu.round(3).tolist()],
            geodetic=[tuple(p) for p in latest.points.geodetic(site).round(8).tolist()],
        )
    assert row is not None
    return _body(scans, vehicle_id, row.frame)


@router.get(
    "/vehicles/{vehicle_id}/scans",
    response_model=ScanPage,
    openapi_extra=requires(Permission.READ),
)
async def scans_between(
    vehicle_id: VehicleIdPath,
    scans: ScansDep,
    fleet: RegistryDep,
    start: Annotated[Moment | None, time_query("end - 1 min")] = None,
    end: Annotated[Moment | None, time_query("now")] = None,
    limit: Annotated[int, Query(ge=1, le=MAX_SCANS_PAGE)] = 20,
) -> ScanPage:
    """Stored scans in a time range, oldest first, as world points."""
    fleet.get(vehicle_id)
    start_at, end_at = time_range(start, end, DEFAULT_SCAN_HISTORY_S)
    rows = await asyncio.to_thread(
        scans.repository.between, vehicle_id, start_at, end_at, limit + 1
    )
    bodies = [_body(scans, vehicle_id, row.frame) for row in rows[:limit]]
    site = scans.site
    return ScanPage(
        vehicle_id=vehicle_id,
        start=start_at,
        end=end_at,
        limit=limit,
        site=None if site is None else site_origin(site),
        scans=bodies,
        truncated=len(rows) > limit,
    )


@router.get(
    "/vehicles/{vehicle_id}/scans/diagnostics",
    response_model=ScanDiagnosticsBody,
    openapi_extra=requires(Permission.READ),
)
async def scan_diagnostics(
    vehicle_id: VehicleIdPath, scans: ScansDep, fleet: RegistryDep
) -> ScanDiagnosticsBody:
    """What the hub made of this vehicle's scans (received, stored, refused by reason), and
    what the agent's LIDAR parser decoded and dropped by reason, as the agent last said."""
    fleet.get(vehicle_id)
    counts = scans.diagnostics_of(vehicle_id)
    return ScanDiagnosticsBody(
        vehicle_id=vehicle_id,
        received=counts.received,
        live=counts.live,
        replayed=counts.replayed,
        stored=counts.stored,
        cleaned_ranges=counts.cleaned_ranges,
        rejected=dict(counts.rejected),
        source=counts.source,
        source_counts=dict(counts.source_counts),
    )


@router.get(
    "/scans/map",
    response_model=PointMapView,
    openapi_extra=requires(Permission.READ),
    responses={200: {"content": {"application/octet-stream": {}}}},
)
async def point_map(
    scans: ScansDep,
    format: Annotated[Literal["json", "ply"], Query(description="json, or a PLY file")] = "json",
    limit: Annotated[int, Query(ge=1, le=MAX_MAP_POINTS)] = 100_000,
) -> PointMapView | Response:
    """The site's voxel point map (the most recently seen voxels, up to ``limit``); the
    live feed sends the same as ``point_map`` to a ``subscribe_map``."""
    if format == "ply":
        site = site_origin(scans.site)
        origin = "unset" if site is None else f"{site.lat},{site.lon},{site.alt_msl}"
        return Response(
            ply_bytes(
                scans.point_map.points(limit), f"gcs point map: ENU metres, site origin {origin}"
            ),
            media_type="application/octet-stream",
            headers={"Content-Disposition": 'attachment; filename="pointmap.ply"'},
        )
    return point_map_view(scans, limit)


@router.get(
    "/scans/obstacles",
    response_model=list[Obstacle],
    openapi_extra=requires(Permission.READ),
)
async def obstacles(scans: ScansDep, refresh: RefreshObstaclesDep) -> list[Obstacle]:
    """Clusters in the point map (above the ground), with their extents in site ENU; an
    obstacle keeps its id while it is seen (found and gone are events, kind "obstacle")."""
    return obstacle_views(await refresh(), scans.site)


FLIGHT_SCAN_PAGE = 500


def _flight_points(
    scans: ScanService, logbook: Logbook, flight_id: int
) -> tuple[str, PointMap, LocalFrame | None]:
    """A flight's scans as one point map at the site map's voxel size: bounded by the
    surfaces the flight saw, however long it was."""
    flight = logbook.flight(flight_id)
    end = flight_end(flight)
    points = PointMap(scans.point_map.voxel_m, scans.point_map.max_voxels)
    start, site = flight.start_time, scans.site
    while True:
        rows = scans.repository.between(flight.vehicle_id, start, end, FLIGHT_SCAN_PAGE)
        for row in rows:
            frame = decode_scan(row.frame)
            site = scans.site_for(frame)
            points.add(world_points(frame, site).enu, row.time)
        if len(rows) < FLIGHT_SCAN_PAGE:
            return f"{flight.vehicle_id}_flight{flight.id}", points, site
        start = math.nextafter(rows[-1].time, math.inf)


@router.get(
    "/flights/{flight_id}/points.ply",
    openapi_extra=requires(Permission.READ),
    response_class=Response,
    responses={
        200: {"content": {"application/octet-stream": {}}},
        404: {"description": "No such flight"},
    },
)
async def flight_points(flight_id: FlightIdPath, scans: ScansDep, logbook: LogbookDep) -> Response:
    """The world points of a flight's scans (site east/north/up metres, voxel-downsampled
    like the point map) as a PLY file, for CloudCompare, PDAL or MeshLab."""
    name, points, site = await asyncio.to_thread(_flight_points, scans, logbook, flight_id)
    shown = site_origin(site)
    origin = "unset" if shown is None else ",".join(str(v) for v in shown.model_dump().values())
    return Response(
        ply_bytes(points.points(), f"gcs flight points: ENU metres, site origin {origin}"),
        media_type="application/octet-stream",
        headers={"Content-Disposition": f'attachment; filename="{name}.ply"'},
    )
