"""Survey areas from other tools' files: a QGC Survey item's (qgc_plan.py), a GeoJSON
polygon, or a KML polygon (areas drawn in Google Earth); and a mission's path as GeoJSON.

KML is parsed with defusedxml: a file that declares entities is refused as it is read,
before anything is expanded (a billion laughs, or a quadratic blowup that stays under
expat's own amplification limit: 5 MB of KML could otherwise become 500 MB).
"""

from __future__ import annotations

import json
import xml.etree.ElementTree as ElementTree
from collections.abc import Sequence
from typing import Any

from defusedxml import DefusedXmlException
from defusedxml.ElementTree import fromstring as parse_xml

from backend.survey.files.items import POSITIONLESS_FRAME, InteropError, check_size, check_vertices
from backend.survey.files.qgc_plan import read_qgc_survey
from protocol.messages import MissionItem

_KML = "{http://www.opengis.net/kml/2.2}"


def read_area_file(kind: str, text: str, max_vertices: int | None = None) -> dict[str, Any]:
    """A survey request's fields from an area file: "plan" (a QGC Survey: its area,
    camera and settings), "kml" or "geojson" (the area)."""
    if kind == "plan":
        return read_qgc_survey(text, max_vertices)
    if kind == "kml":
        return {"area": read_kml_polygon(text, max_vertices)}
    if kind == "geojson":
        return {"area": read_geojson_polygon(text, max_vertices)}
    raise InteropError(f"unknown area file format {kind!r}; plan, kml or geojson")


def mission_path_geojson(items: Sequence[MissionItem]) -> dict[str, Any]:
    """The mission's positions as a GeoJSON LineString ([lon, lat, alt])."""
    coordinates = [
        [item.lon, item.lat, item.alt]
        for item in items
        if item.frame != POSITIONLESS_FRAME and (item.lat or item.lon)
    ]
    return {
        "type": "Feature",
        "properties": {},
        "geometry": {"type": "LineString", "coordinates": coordinates},
    }


def read_geojson_polygon(text: str | bytes, max_vertices: int | None = None) -> dict[str, Any]:
    """A Polygon from a GeoJSON geometry, Feature or FeatureCollection (its first)."""
    try:
        document = json.loads(text)
    except (ValueError, RecursionError) as error:
        raise InteropError(f"not GeoJSON: {error}") from None
    while isinstance(document, dict):
        kind = document.get("type")
        if kind == "Polygon":
            rings = document.get("coordinates")
            if isinstance(rings, list):
                check_vertices(sum(len(r) for r in rings if isinstance(r, list)), max_vertices)
            return {"type": "Polygon", "coordinates": rings}
        if kind == "Feature":
            document = document.get("geometry")
        elif kind == "FeatureCollection" and document.get("features"):
            document = document["features"][0]
        else:
            break
    raise InteropError("the GeoJSON holds no Polygon")


def read_kml_polygon(data: str | bytes, max_vertices: int | None = None) -> dict[str, Any]:
    """The first Polygon of a KML file (Google Earth), holes included, as GeoJSON."""
    raw = data.encode() if isinstance(data, str) else data
    check_size(len(raw))
    try:
        # KML has no use for entities (nor for external ones, nor DTDs that fetch).
        root = parse_xml(raw, forbid_dtd=False, forbid_entities=True, forbid_external=True)
    except DefusedXmlException:
        raise InteropError(
            "the KML file declares entities; a KML file has none (refused unread)"
        ) from None
    except ElementTree.ParseError as error:
        raise InteropError(f"not a KML file: {error}") from None
    polygon = _first(root, "Polygon")
    if polygon is None:
        raise InteropError("the KML file holds no Polygon")

    def triples(boundary: ElementTree.Element) -> list[str]:
        node = _first(boundary, "coordinates")
        return ("" if node is None else (node.text or "")).split()

    def ring(found: list[str], what: str) -> list[list[float]]:
        if not found:
            raise InteropError(f"the KML polygon's {what} has no coordinates")
        points = []
        for k, triple in enumerate(found):
            try:
                values = [float(v) for v in triple.split(",")]
            except ValueError:
                raise InteropError(f"the {what}'s point {k + 1} is not lon,lat[,alt]") from None
            points.append(values[:2])
        if points[0] != points[-1]:
            points.append(points[0])
        return points

    outer = _first(polygon, "outerBoundaryIs")
    if outer is None:
        raise InteropError("the KML polygon has no outerBoundaryIs")
    inners = [e for e in polygon.iter() if e.tag in (f"{_KML}innerBoundaryIs", "innerBoundaryIs")]
    found = [triples(outer), *(triples(inner) for inner in inners)]
    # Counted before any coordinate is parsed: a huge ring is refused at its size.
    check_vertices(sum(len(points) for points in found), max_vertices)
    rings = [ring(found[0], "outline")]
    for k, points in enumerate(found[1:]):
        rings.append(ring(points, f"hole {k + 1}"))
    return {"type": "Polygon", "coordinates": rings}


def _first(node: ElementTree.Element, tag: str) -> ElementTree.Element | None:
    """The first element named `tag`, in KML's namespace or none."""
    return next((e for e in node.iter() if e.tag in (f"{_KML}{tag}", tag)), None)
