"""GeoJSON polygons to and from the planner's local metric frame.

The frame is a tangent plane (common.geodesy.LocalFrame) at the area's centre: exact
projections with no zone, so an area across a UTM zone boundary or the antimeridian is
planned like any other. Kept to areas a few tens of kilometres across, where the plane
departs from the ground by centimetres.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

from shapely.geometry import Polygon

from backend.survey.planning.planner import MAX_VERTICES, PlanError
from common.geodesy import LocalFrame

MAX_EXTENT_M = 50_000.0


def _ring(coords: Any, what: str) -> list[tuple[float, float]]:
    if not isinstance(coords, Sequence) or len(coords) < 4:
        raise PlanError(f"{what} needs at least 4 positions (3 corners and the first again)")
    out = []
    for i, pos in enumerate(coords):
        if not isinstance(pos, Sequence) or len(pos) < 2:
            raise PlanError(f"{what} position {i} must be [longitude, latitude]")
        lon, lat = float(pos[0]), float(pos[1])
        if not (-180 <= lon <= 180 and -90 <= lat <= 90) or math.isnan(lon + lat):
            raise PlanError(f"{what} position {i} is not a longitude/latitude: {pos}")
        out.append((lon, lat))
    return out


def polygon_from_geojson(geometry: Any) -> tuple[Polygon, LocalFrame]:
    """A GeoJSON Polygon (lon, lat; first ring the outline, the others holes) in metres."""
    if not isinstance(geometry, dict) or geometry.get("type") != "Polygon":
        raise PlanError("the area must be a GeoJSON geometry of type Polygon")
    rings = geometry.get("coordinates")
    if not isinstance(rings, Sequence) or not rings:
        raise PlanError("the area's coordinates must be a list of rings")
    if sum(len(r) for r in rings if isinstance(r, Sequence)) > MAX_VERTICES:
        raise PlanError(f"the area has more than {MAX_VERTICES} vertices")
    outline = _ring(rings[0], "the outline")
    holes = [_ring(r, f"hole {i + 1}") for i, r in enumerate(rings[1:])]
    lon0, lat0 = outline[0]
    first = LocalFrame(lat0, lon0)
    xs, ys = zip(*(first.to_local(lat, lon) for lon, lat in outline), strict=True)
    lat_c, lon_c = first.to_geo((min(xs) + max(xs)) / 2, (min(ys) + max(ys)) / 2)
    frame = LocalFrame(lat_c, lon_c)
    local = [frame.to_local(lat, lon) for lon, lat in outline]
    extent = max(math.dist(p, (0.0, 0.0)) for p in local)
    if extent > MAX_EXTENT_M:
        raise PlanError(
            f"the area reaches {extent / 1000:.0f} km from its centre; "
            f"at most {MAX_EXTENT_M / 1000:.0f} km"
        )
    polygon = Polygon(local, [[frame.to_local(lat, lon) for lon, lat in h] for h in holes])
    return polygon, frame
