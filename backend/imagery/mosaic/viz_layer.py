"""A survey's mosaic in the 3D view: one textured plane on the ground.

The texture is the mosaic's own tiles at the finest zoom whose tiles over the mosaic's
extent fit ``MAX_TEXTURE_PX`` a side (the tile pyramid goes down to 64 times coarser
than the photos, so one zoom nearly always fits; the coarsest is scaled down if not).
Tiles are Web Mercator squares: over a survey's few hundred metres their rectangle is a
rectangle in the scene's east-north-up metres to well under a centimetre, so the plane
is laid from its south-west and north-east corners. It lies at the origin's height (the
first home the fleet reported), just above the ground grid, and is redrawn at most every
``REFRESH_S`` while photos arrive (a new texture is a megabyte to every viewer).
"""

from __future__ import annotations

import asyncio
from collections.abc import Callable, Iterable
from dataclasses import dataclass

import cv2
import numpy as np
import numpy.typing as npt
import viser

from backend.imagery.mosaic.georef import TILE_PX
from backend.imagery.mosaic.service import MosaicService, UnknownMosaic
from backend.imagery.mosaic.store import TileSpan, TileStore
from backend.viz3d.scene import MOSAIC, FleetScene

MAX_TEXTURE_PX = 1024
REFRESH_S = 3.0
GROUND_LIFT_M = 0.05  # above the grid, which lies at the origin's height
# viser's image plane has the image's top row at its -y; turned half round its x axis,
# the top row is north (+y) and the first column west (-x).
NORTH_UP = (0.0, 1.0, 0.0, 0.0)


@dataclass(frozen=True)
class Overview:
    """A mosaic's extent as one image (RGBA, north up) and its corners in degrees."""

    image: npt.NDArray[np.uint8]
    west: float
    south: float
    east: float
    north: float
    zoom: int


def overview(store: TileStore, max_px: int = MAX_TEXTURE_PX) -> Overview | None:
    """The store's tiles over its extent, at most ``max_px`` a side; None without tiles.
    The caller holds the survey's lock (no photo lands mid-read)."""
    if store.max_zoom is None or store.min_zoom is None:
        return None
    chosen: tuple[int, list[tuple[int, int, int]]] | None = None
    for zoom in range(store.max_zoom, store.min_zoom - 1, -1):
        keys = list(store.keys(zoom))
        if not keys:
            continue
        chosen = zoom, keys
        xs, ys = [k[1] for k in keys], [k[2] for k in keys]
        if max(max(xs) - min(xs), max(ys) - min(ys)) + 1 <= max_px // TILE_PX:
            break
    if chosen is None:
        return None
    zoom, keys = chosen
    span = TileSpan.of(zoom, keys)
    image = np.zeros((span.height_px, span.width_px, 4), dtype=np.uint8)
    for key in keys:
        if (bgra := store.pixels(key)) is None:
            continue
        left, top = span.offset_px(key)
        image[top : top + TILE_PX, left : left + TILE_PX] = bgra[:, :, [2, 1, 0, 3]]
    if (side := max(image.shape[:2])) > max_px:
        size = (max(1, image.shape[1] * max_px // side), max(1, image.shape[0] * max_px // side))
        image = np.asarray(cv2.resize(image, size, interpolation=cv2.INTER_AREA), dtype=np.uint8)
    return Overview(image, *span.bounds(), zoom)


class MosaicLayer:
    def __init__(self, scene: FleetScene) -> None:
        self.scene = scene
        self._planes: dict[str, viser.ImageHandle] = {}
        self._revisions: dict[str, int] = {}

    @property
    def mosaics(self) -> list[str]:
        return list(self._planes)

    def show(self, survey_id: str, view: Overview) -> bool:
        """The mosaic's plane (replacing the survey's last); False while the scene has no
        origin."""
        frame = self.scene.frame
        ground = frame.ground(None)
        if ground is None:
            return False
        south_west = frame.place(view.south, view.west, ground)
        north_east = frame.place(view.north, view.east, ground)
        if south_west is None or north_east is None:
            return False
        centre = (south_west + north_east) / 2
        centre[2] += GROUND_LIFT_M
        width, height = (north_east - south_west)[:2]
        with self.scene.batch():
            self._planes[survey_id] = self.scene.server.scene.add_image(
                f"/{MOSAIC.key}/{survey_id}",
                view.image,
                render_width=float(width),
                render_height=float(height),
                format="png",  # keeps what no photo covers transparent
                cast_shadow=False,
                receive_shadow=False,
                wxyz=NORTH_UP,
                position=centre,
            )
            self.scene.show_layer(MOSAIC)
        return True

    def remove(self, survey_id: str) -> None:
        self._revisions.pop(survey_id, None)
        if (plane := self._planes.pop(survey_id, None)) is not None:
            with self.scene.batch():
                plane.remove()

    def refresh(self, mosaics: MosaicService, survey_ids: Iterable[str]) -> None:
        """Redraw each of these surveys' mosaics that has changed since it was drawn, and
        take out the others (blocking: reads tiles; call it in a thread)."""
        wanted = set(survey_ids)
        for gone in set(self._planes) - wanted:
            self.remove(gone)
        for survey_id in sorted(wanted):
            try:
                survey = mosaics.survey(survey_id)
            except UnknownMosaic:
                continue  # no photo of it has reached the mosaic
            revision = survey.store.revision
            if self._revisions.get(survey_id) == revision:
                continue
            with survey.lock:
                view = overview(survey.store)
            if view is not None and self.show(survey_id, view):
                self._revisions[survey_id] = revision

    async def follow(
        self,
        mosaics: MosaicService,
        surveys: Callable[[], Iterable[str]],
        interval_s: float = REFRESH_S,
    ) -> None:
        """Keep the planes of ``surveys()`` (read on the hub's loop) up to date."""
        while True:
            await asyncio.to_thread(self.refresh, mosaics, list(surveys()))
            await asyncio.sleep(interval_s)
