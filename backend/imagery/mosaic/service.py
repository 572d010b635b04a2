"""The live mosaic: stored photos in, each survey's tiles out, while the fleet flies.

``add_photo`` only queues (bounded: an upload burst waits for room rather than filling
memory); ``run`` takes photos one by one and does the work in a thread, off the event
loop. Each survey has a lock that the worker and the exports hold, so a survey's tiles are
never written by two hands at once. A photo that cannot go into the map (no usable pose,
too far from its survey, corrupt, the wrong size) is counted with its reason, and the
mosaic goes on.
"""

from __future__ import annotations

import asyncio
import logging
import re
import threading
import time
from collections import OrderedDict
from collections.abc import Awaitable, Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from backend.imagery.mosaic.engine import Applied, PhotoError, apply_photo, decode
from backend.imagery.mosaic.export import ExportError, export
from backend.imagery.mosaic.georef import GeorefError, footprint, native_zoom, pixel_to_lonlat
from backend.imagery.mosaic.photo import StoredPhoto
from backend.imagery.mosaic.progress import (
    MAX_FAILURES_KEPT,
    Coverage,
    MosaicProgress,
    PhotoFailure,
    VehicleCounts,
)
from backend.imagery.mosaic.store import TileKey, TileStore, atomic_write

log = logging.getLogger(__name__)

SURVEY_ID = re.compile(r"^[A-Za-z0-9_-][A-Za-z0-9_.-]{0,79}$")
AreaLookup = Callable[[str], Awaitable[dict[str, Any] | None]]
Listener = Callable[[StoredPhoto, Applied | None], None]
OVERVIEW_LEVELS = 6  # zooms below the native one: 64 times coarser covers a survey in a tile
MAX_DISTANCE_M = 2000.0  # a photo's nadir this far outside its survey's area is refused


BASEMAP_NAME_MAX = 64  # backend/mapping/tiles.py NAME_PATTERN
ENCODED_CACHE = 2048  # tiles, about 60 MB of JPEG


@dataclass(frozen=True, slots=True)
class ServedTile:
    data: bytes
    media_type: str
    version: int


class UnknownMosaic(LookupError):
    """No photo of that survey has reached the mosaic."""


@dataclass
class SurveyMosaic:
    store: TileStore
    coverage: Coverage
    progress: MosaicProgress
    lock: threading.Lock


class MosaicService:
    def __init__(
        self,
        folder: Path,
        area_of: AreaLookup,
        *,
        queue_limit: int = 64,
        overview_levels: int = OVERVIEW_LEVELS,
        max_distance_m: float = MAX_DISTANCE_M,
    ) -> None:
        self.folder = folder
        self._area_of = area_of
        self._queue: asyncio.Queue[StoredPhoto] = asyncio.Queue(queue_limit)
        self._surveys: dict[str, SurveyMosaic] = {}
        self._opening = asyncio.Lock()
        self.overview_levels = overview_levels
        self.max_distance_m = max_distance_m
        self.listeners: list[Listener] = []
        self._encoded: OrderedDict[tuple[str, TileKey, int], ServedTile] = OrderedDict()
        self._encoded_lock = threading.Lock()

    # -- in ----------------------------------------------------------------------------

    async def add_photo(self, photo: StoredPhoto) -> None:
        """Queue a stored photo for its survey's mosaic (waits while the queue is full)."""
        survey = await self._open(photo.survey_id)
        survey.progress.pending += 1
        await self._queue.put(photo)

    async def run(self) -> None:
        """The worker; cancel it to stop (the photo in hand is finished first)."""
        while True:
            photo = await self._queue.get()
            try:
                await asyncio.shield(asyncio.to_thread(self._process, photo))
                if self._queue.empty():
                    # A lull: what is in memory goes to disk while nothing waits.
                    await asyncio.shield(asyncio.to_thread(self._flush, photo.survey_id))
            finally:
                self._queue.task_done()

    def close(self) -> None:
        """Every survey's tiles to disk (at shutdown, after ``run`` is cancelled; waits
        for a photo still in hand)."""
        for survey_id in list(self._surveys):
            self._flush(survey_id)

    def _flush(self, survey_id: str) -> None:
        survey = self._surveys[survey_id]
        with survey.lock:
            survey.store.flush()

    async def idle(self) -> None:
        """Until every queued photo is done (tests and the benchmark wait on it)."""
        await self._queue.join()

    # -- out ---------------------------------------------------------------------------

    def progress(self, survey_id: str) -> MosaicProgress:
        return self._known(survey_id).progress.model_copy(deep=True)

    def surveys(self) -> list[str]:
        return sorted(self._surveys)

    async def load(self) -> None:
        """The mosaics already on disk (from before a restart)."""
        if not self.folder.is_dir():
            return
        for path in sorted(self.folder.iterdir()):
            if path.is_dir() and SURVEY_ID.match(path.name):
                await self._open(path.name)

    def tile(self, survey_id: str, z: int, x: int, y: int) -> ServedTile | None:
        """A tile as served, or None outside the mosaic (blocking: call it in a thread).
        Encoded once per version: the map asks for the same tiles again and again."""
        store = self._known(survey_id).store
        key: TileKey = (z, x, y)
        version = store.versions.get(key)
        if version is None:
            return None
        cached = (survey_id, key, version)
        with self._encoded_lock:
            if (served := self._encoded.get(cached)) is not None:
                self._encoded.move_to_end(cached)
                return served
        encoded = store.encode(key)
        if encoded is None:
            return None
        served = ServedTile(encoded[0], encoded[1], version)
        with self._encoded_lock:
            self._encoded[cached] = served
            while len(self._encoded) > ENCODED_CACHE:
                self._encoded.popitem(last=False)
        return served

    def export(self, survey_id: str, kind: str) -> Path:
        """The mosaic as a file (blocking: call it in a thread); ExportError if it has no
        tiles yet. Under the survey's lock: no photo lands mid-export."""
        survey = self._known(survey_id)
        with survey.lock:
            return export(survey.store, kind, survey.store.folder / "exports", survey_id)

    def install_basemap(self, survey_id: str, tiles_folder: Path) -> str:
        """The mosaic as ``mosaic-<survey id>.pmtiles`` in the offline tiles folder, where
        the dashboard lists it among the base maps; its set name (blocking: a thread)."""
        name = f"mosaic-{survey_id}"
        if len(name) > BASEMAP_NAME_MAX:
            raise ExportError(f"survey id {survey_id!r} is too long for a tile set name")
        made = self.export(survey_id, "pmtiles")
        atomic_write(tiles_folder / f"{name}.pmtiles", made.read_bytes())
        return name

    def survey(self, survey_id: str) -> SurveyMosaic:
        return self._known(survey_id)

    # -- inside ------------------------------------------------------------------------

    def _known(self, survey_id: str) -> SurveyMosaic:
        survey = self._surveys.get(survey_id)
        if survey is None:
            raise UnknownMosaic(survey_id)
        return survey

    async def _open(self, survey_id: str) -> SurveyMosaic:
        if not SURVEY_ID.match(survey_id):
            raise ValueError(f"{survey_id!r} is not a survey id")
        async with self._opening:
            if survey_id in self._surveys:
                return self._surveys[survey_id]
            try:
                area = await self._area_of(survey_id)
            except LookupError:
                area = None
            folder = self.folder / survey_id
            survey = await asyncio.to_thread(_open_survey, folder, survey_id, area)
            self._surveys[survey_id] = survey
            return survey

    def _process(self, photo: StoredPhoto) -> None:
        survey = self._surveys[photo.survey_id]
        applied: Applied | None = None
        with survey.lock:
            started = time.perf_counter()
            try:
                applied = self._apply(survey, photo)
            except (GeorefError, PhotoError, OSError) as error:
                self._failed(survey, photo, str(error))
            except Exception as error:  # a bug must cost one photo, never the mosaic
                log.exception("mosaic: photo %s of survey %s", photo.photo_id, photo.survey_id)
                self._failed(survey, photo, f"internal error: {error.__class__.__name__}")
            finally:
                survey.progress.pending = max(0, survey.progress.pending - 1)
                _save_progress(survey)
            log.debug("mosaic: photo %s in %.2f s", photo.photo_id, time.perf_counter() - started)
        for listener in self.listeners:
            listener(photo, applied)

    def _apply(self, survey: SurveyMosaic, photo: StoredPhoto) -> Applied:
        pose = photo.pose
        off_by = survey.coverage.distance_m(pose.lat, pose.lon)
        if off_by > self.max_distance_m:
            raise GeorefError(
                f"the photo was taken {off_by:.0f} m from the survey's area; more than "
                f"{self.max_distance_m:g} m away it cannot belong to it"
            )
        place = footprint(pose, photo.camera)
        store = survey.store
        if store.max_zoom is None:
            # The first photo sets the survey's tile pyramid; the rest share it.
            store.max_zoom = native_zoom(place.gsd_m, pose.lat)
            store.min_zoom = max(0, store.max_zoom - self.overview_levels)
        image = decode(
            photo.path.read_bytes(), photo.camera.image_width_px, photo.camera.image_height_px
        )
        applied = apply_photo(store, image, place)
        store.revision += 1
        survey.coverage.add(place.corners_lonlat)
        survey.coverage.save(store.folder / "coverage.json")
        progress = survey.progress
        progress.processed += 1
        progress.by_vehicle.setdefault(photo.vehicle_id, VehicleCounts()).processed += 1
        _refresh(survey)
        return applied

    def _failed(self, survey: SurveyMosaic, photo: StoredPhoto, reason: str) -> None:
        log.info("mosaic: photo %s refused: %s", photo.photo_id, reason)
        progress = survey.progress
        progress.failed += 1
        progress.by_vehicle.setdefault(photo.vehicle_id, VehicleCounts()).failed += 1
        progress.failures.append(
            PhotoFailure(photo_id=photo.photo_id, vehicle_id=photo.vehicle_id, reason=reason)
        )
        del progress.failures[:-MAX_FAILURES_KEPT]


def _open_survey(folder: Path, survey_id: str, area: dict[str, Any] | None) -> SurveyMosaic:
    store = TileStore.open(folder)
    coverage = Coverage(area)
    coverage.load(folder / "coverage.json")
    saved = folder / "progress.json"
    if saved.is_file():
        progress = MosaicProgress.model_validate_json(saved.read_text())
        progress.pending = 0
    else:
        progress = MosaicProgress(survey_id=survey_id)
    survey = SurveyMosaic(store, coverage, progress, threading.Lock())
    _refresh(survey)
    return survey


def _refresh(survey: SurveyMosaic) -> None:
    progress, store, coverage = survey.progress, survey.store, survey.coverage
    progress.revision = store.revision
    progress.min_zoom, progress.max_zoom = store.min_zoom, store.max_zoom
    progress.coverage_pct = coverage.percent()
    progress.outline = coverage.outline()
    progress.bounds = coverage.bounds()


def _save_progress(survey: SurveyMosaic) -> None:
    atomic_write(survey.store.folder / "progress.json", survey.progress.model_dump_json().encode())


__all__ = ["MosaicService", "StoredPhoto", "UnknownMosaic", "pixel_to_lonlat"]
