"""The point map and its obstacles as clients see them, over REST and on the live feed
alike: one shape for both (protocol.messages)."""

from __future__ import annotations

from backend.scans.pointmap import MapObstacle
from backend.scans.service import ScanService
from common.geodesy import LocalFrame
from protocol.messages import Obstacle, PointMapView, SiteOrigin


def site_origin(site: LocalFrame | None) -> SiteOrigin | None:
    if site is None:
        return None
    origin = site.origin
    return SiteOrigin(lat=origin.lat, lon=origin.lon, alt_msl=origin.alt)


def point_map_view(scans: ScanService, limit: int) -> PointMapView:
    """The map's newest ``limit`` voxels, to the centimetre."""
    points = scans.point_map.points(limit)
    return PointMapView(
        site=site_origin(scans.site),
        voxel_m=scans.point_map.voxel_m,
        voxels=len(scans.point_map),
        evicted=scans.point_map.evicted,
        points=[tuple(p) for p in points.round(2).tolist()],
    )


def obstacle_views(found: list[MapObstacle], site: LocalFrame | None) -> list[Obstacle]:
    if site is None:
        return []
    views = []
    for o in found:
        corners = [
            (o.east_min, o.north_min),
            (o.east_max, o.north_min),
            (o.east_max, o.north_max),
            (o.east_min, o.north_max),
        ]
        outline = [site.to_geo(east, north) for east, north in corners]
        views.append(Obstacle(**vars(o), outline=outline))
    return views
