"""The survey planner's test areas (metres), shared by
tests/unit/survey/planning/test_planner.py and bench/bench_survey.py, so the benchmark's
path ratios are the tested shapes'."""

from __future__ import annotations

from typing import Any

from shapely.geometry import Polygon, box

from backend.survey.planning.geo import polygon_from_geojson
from common.geodesy import LocalFrame

SHAPES = {
    "convex": Polygon([(0, 0), (900, -100), (1000, 700), (200, 900)]),
    "L": Polygon([(0, 0), (600, 0), (600, 200), (200, 200), (200, 600), (0, 600)]),
    "U": Polygon(
        [(0, 0), (600, 0), (600, 600), (450, 600), (450, 150), (150, 150), (150, 600), (0, 600)]
    ),
    "holed": Polygon(
        [(0, 0), (600, 0), (600, 600), (0, 600)], [[(200, 200), (400, 200), (400, 400), (200, 400)]]
    ),
    "thin": box(0, 0, 2000, 60),
}


def zone_straddling() -> Polygon:
    # 6°E is the boundary of UTM zones 31 and 32: this area lies across it.
    ring = [[5.99, 47.0], [6.01, 47.0], [6.012, 47.01], [5.992, 47.012], [5.99, 47.0]]
    polygon, _ = polygon_from_geojson({"type": "Polygon", "coordinates": [ring]})
    return polygon


def shape(name: str) -> Polygon:
    return zone_straddling() if name == "zone-straddling" else SHAPES[name]


def geojson_area(frame: LocalFrame, corners: list[tuple[float, float]]) -> dict[str, Any]:
    """A survey area as the API takes it: a closed GeoJSON polygon (longitude first) through
    ``corners``, each (east, north) in metres from ``frame``'s origin."""
    ring = [list(reversed(frame.to_geo(x, y))) for x, y in [*corners, corners[0]]]
    return {"type": "Polygon", "coordinates": [ring]}


def kml_polygon(vertices: int) -> str:
    """A KML area of ``vertices`` corners (a long thin sliver near 47°N 8°E): the large
    import that the hub's vertex limit and its import flood are about."""
    points = " ".join(f"{8 + k * 1e-6:.6f},47.000000" for k in range(vertices - 1))
    return (
        '<kml xmlns="http://www.opengis.net/kml/2.2"><Placemark><Polygon><outerBoundaryIs>'
        f"<LinearRing><coordinates>{points} 8.5,47.5</coordinates></LinearRing>"
        "</outerBoundaryIs></Polygon></Placemark></kml>"
    )
