"""A survey mosaic's progress: photos processed and failed (with reasons) per vehicle, and
how much of the survey's area the photos' footprints cover, as a percentage and an outline.

Footprints are unioned on the survey's own tangent plane (the planner's frame,
backend/survey/planning/geo.py), in metres, so the percentage is of true area. Saved as
``progress.json`` beside the tiles, so a restarted hub reports what it had.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt
from pydantic import BaseModel, Field
from shapely import to_geojson, transform
from shapely.geometry import Point, Polygon, mapping, shape
from shapely.geometry.base import BaseGeometry

from backend.imagery.mosaic.store import atomic_write
from backend.survey.planning.geo import polygon_from_geojson
from backend.survey.planning.planner import PlanError
from common.geodesy import LocalFrame

MAX_FAILURES_KEPT = 200  # the latest reasons; the counts go on


class PhotoFailure(BaseModel):
    photo_id: str
    vehicle_id: str
    reason: str


class VehicleCounts(BaseModel):
    processed: int = 0
    failed: int = 0


class MosaicProgress(BaseModel):
    survey_id: str
    processed: int = 0
    failed: int = 0
    pending: int = Field(default=0, description="photos queued for this survey, not yet done")
    by_vehicle: dict[str, VehicleCounts] = Field(default_factory=dict)
    failures: list[PhotoFailure] = Field(
        default_factory=list, description=f"the latest {MAX_FAILURES_KEPT} failures"
    )
    coverage_pct: float | None = Field(
        default=None, description="percent of the survey's area under a photo; None: no area"
    )
    outline: dict[str, Any] | None = Field(
        default=None, description="GeoJSON (lon, lat) of the covered ground"
    )
    revision: int = Field(default=0, description="photos applied to the tiles so far")
    min_zoom: int | None = None
    max_zoom: int | None = None
    bounds: tuple[float, float, float, float] | None = Field(
        default=None, description="west, south, east, north of the covered ground"
    )


class Coverage:
    """The union of the footprints, on the survey area's plane (or the first photo's)."""

    def __init__(self, area_geojson: dict[str, Any] | None) -> None:
        self.area: Polygon | None = None
        self.frame: LocalFrame | None = None
        if area_geojson is not None:
            try:
                self.area, self.frame = polygon_from_geojson(area_geojson)
            except PlanError:
                self.area = None
        self.covered: BaseGeometry = Polygon()

    def add(self, corners_lonlat: list[tuple[float, float]]) -> None:
        if self.frame is None:
            lon, lat = corners_lonlat[0]
            self.frame = LocalFrame(lat, lon)
        frame = self.frame
        local = Polygon([frame.to_local(lat, lon) for lon, lat in corners_lonlat])
        self.covered = self.covered.union(local.buffer(0))

    def distance_m(self, lat: float, lon: float) -> float:
        """How far a point is from the survey's area (0 inside; 0 when there is none)."""
        if self.area is None or self.frame is None:
            return 0.0
        return float(self.area.distance(Point(self.frame.to_local(lat, lon))))

    def percent(self) -> float | None:
        if self.area is None or self.area.area <= 0:
            return None
        return 100.0 * self.covered.intersection(self.area).area / self.area.area

    def outline(self) -> dict[str, Any] | None:
        if self.frame is None or self.covered.is_empty:
            return None
        shape_ = self.covered if self.area is None else self.covered.intersection(self.area)
        frame = self.frame

        def to_lonlat(points: npt.NDArray[np.float64]) -> npt.NDArray[np.float64]:
            pairs = [frame.to_geo(float(e), float(n)) for e, n in points]
            return np.array([(lon, lat) for lat, lon in pairs]).reshape(-1, 2)

        geo: dict[str, Any] = json.loads(to_geojson(transform(shape_.simplify(0.05), to_lonlat)))
        return geo

    def bounds(self) -> tuple[float, float, float, float] | None:
        outline = self.outline()
        if outline is None:
            return None
        west, south, east, north = shape(outline).bounds
        return west, south, east, north

    def save(self, path: Path) -> None:
        """The union, in the plane's metres, with the plane's origin (which is the first
        photo's where the survey has no area)."""
        origin = None if self.frame is None else [self.frame.origin.lat, self.frame.origin.lon]
        saved = {"origin": origin, "covered": mapping(self.covered)}
        atomic_write(path, json.dumps(saved).encode())

    def load(self, path: Path) -> None:
        if not path.is_file():
            return
        saved = json.loads(path.read_text())
        if self.frame is None and saved["origin"] is not None:
            self.frame = LocalFrame(*saved["origin"])
        self.covered = shape(saved["covered"])
