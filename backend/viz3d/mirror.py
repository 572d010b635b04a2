"""Keeps the 3D scene in step with the fleet, in batches at a bounded rate.

Vehicle changes arrive on the bus as they happen (50 vehicles at 10 Hz is 500 a second).
The mirror takes them newest-wins per vehicle, and at most once per period applies what
has changed as one atomic scene update: the browser gets a bounded number of updates a
second whatever the fleet's size and rate, and never a stale state before a newer one.
Scans are taken the same way (each vehicle's newest, at most once per period), and the
accumulated point map, which only grows slowly, less often. Surveys' lanes and mosaics
have a layer module each (backend/survey/viz_layer.py, backend/imagery/mosaic/viz_layer.py),
and a feature package may bring its own (``SceneLayer``: the formation's,
backend/formation/scene_layer.py); the mirror runs them beside its own work.
"""

from __future__ import annotations

import asyncio
import logging
import time
from collections.abc import Awaitable, Callable, Iterable, Iterator

from backend.errors import VehicleNotFound
from backend.fleet.registry import FleetRegistry
from backend.imagery.mosaic.service import MosaicService
from backend.imagery.mosaic.viz_layer import MosaicLayer
from backend.realtime.bus import Bus, LatestSubscription, Topic
from backend.scans.pointmap import Array, find_obstacles
from backend.scans.service import ScanDelivery, ScanService
from backend.survey.service import SurveyService
from backend.survey.viz_layer import SurveyLanes
from backend.viz3d.frame import HomeAltitude
from backend.viz3d.scene import FleetScene
from common.geodesy import LocalFrame

log = logging.getLogger(__name__)

RESTART_S = 5.0  # before a failed layer's loop is started again

# The point map is redrawn at most this often, and only its newest voxels: it is the
# scene's heaviest message, and it changes little from one second to the next.
POINT_MAP_INTERVAL_S = 2.0
POINT_MAP_MAX_POINTS = 100_000
POINT_MAP_SHARE = 10.0

# A feature's own layer: given the scene, each vehicle's home altitude and the mirror's
# interval, the loop that draws it. Made once per mirror, as the mirror's own layers
# are, so a restarted loop still knows what its layer drew.
SceneLayer = Callable[[FleetScene, HomeAltitude, float], Callable[[], Awaitable[None]]]


class SceneMirror:
    def __init__(
        self,
        scene: FleetScene,
        bus: Bus,
        registry: FleetRegistry,
        interval_s: float,
        scans: ScanService | None = None,
        surveys: SurveyService | None = None,
        mosaics: MosaicService | None = None,
        mosaic_surveys: Callable[[], Iterable[str]] | None = None,
        layers: Iterable[tuple[str, SceneLayer]] = (),
    ) -> None:
        """``mosaic_surveys``: the surveys whose mosaics are drawn (the hub gives those it
        has followed since it started, flying or ended)."""
        self.scene = scene
        self.bus = bus
        self.registry = registry
        self.interval_s = interval_s
        self.scans = scans
        self.surveys = surveys
        self.layers = list(layers)
        self.mosaics = mosaics
        self.mosaic_surveys = mosaic_surveys

    async def run(self) -> None:
        async with asyncio.TaskGroup() as tasks:
            for name, work in self._work():
                tasks.create_task(contained(name, work))

    def _work(self) -> Iterator[tuple[str, Callable[[], Awaitable[None]]]]:
        """Each loop that draws part of the scene, by name."""
        yield "vehicles", self._vehicles
        if self.scans is not None:
            scans = self.scans
            yield "scans", lambda: self._scans(scans)
            yield "point map", lambda: self._point_map(scans)
        if self.surveys is not None:
            surveys, lanes = self.surveys, SurveyLanes(self.scene, self.home_alt)
            yield "survey lanes", lambda: lanes.follow(self.bus, surveys, self.interval_s)
        for name, layer in self.layers:
            yield name, layer(self.scene, self.home_alt, self.interval_s)
        if self.mosaics is not None and self.mosaic_surveys is not None:
            # Made once, as the other layers are: a restarted loop still knows what its
            # layer drew, so it can take those pictures away again.
            mosaics, shown, mosaic = self.mosaics, self.mosaic_surveys, MosaicLayer(self.scene)
            yield "mosaic", lambda: mosaic.follow(mosaics, shown)

    def home_alt(self, vehicle_id: str) -> float | None:
        try:
            state = self.registry.get(vehicle_id).state
        except VehicleNotFound:
            return None
        return None if state is None else state.home_alt_msl

    async def _vehicles(self) -> None:
        updates = LatestSubscription()
        # Subscribe before reading the registry, so no change falls between the two.
        self.bus.subscribe(Topic.VEHICLE_STATE, updates)
        try:
            # viser's calls serialise and compress; a worker thread keeps that off the
            # hub's event loop. One batch at a time: each waits for the one before.
            known = [record.summary() for record in self.registry.all()]
            await asyncio.to_thread(self.scene.apply, known)
            while True:
                batch = await updates.drain()
                await asyncio.to_thread(self.scene.apply, batch)
                # Pacing, not synchronisation: changes arriving meanwhile coalesce.
                await asyncio.sleep(self.interval_s)
        finally:
            self.bus.unsubscribe(Topic.VEHICLE_STATE, updates)

    async def _scans(self, scans: ScanService) -> None:
        updates = LatestSubscription()
        self.bus.subscribe(Topic.SCANS, updates)
        try:
            while True:
                deliveries: list[ScanDelivery] = await updates.drain()
                await asyncio.to_thread(self._show_scans, scans, deliveries)
                await asyncio.sleep(self.interval_s)
        finally:
            self.bus.unsubscribe(Topic.SCANS, updates)

    def _show_scans(self, scans: ScanService, deliveries: list[ScanDelivery]) -> None:
        site = scans.site
        if site is None:
            return
        with self.scene.batch():
            for delivery in deliveries:
                # The service's newest scan of the vehicle, its points already placed
                # (at least as new as the delivery that woke us).
                if (latest := scans.latest.get(delivery.vehicle_id)) is not None:
                    self.scene.show_scan(delivery.vehicle_id, latest.points.enu, site)

    def _show_point_map(self, points: Array, voxel_m: float, site: LocalFrame) -> None:
        self.scene.show_point_map(points, find_obstacles(points, voxel_m), site)

    async def _point_map(self, scans: ScanService) -> None:
        drawn = -1
        while True:
            point_map = scans.point_map
            took = 0.0
            if point_map.version != drawn and scans.site is not None:
                drawn = point_map.version
                # Copied here, on the loop that adds to it; searched and drawn in a thread.
                points = point_map.points(limit=POINT_MAP_MAX_POINTS)
                started = time.monotonic()
                await asyncio.to_thread(self._show_point_map, points, point_map.voxel_m, scans.site)
                took = time.monotonic() - started
            # The obstacle search is pure Python (seconds over a large map): waiting ten
            # times as long as it took keeps it to a tenth of a core, GIL included.
            await asyncio.sleep(max(POINT_MAP_INTERVAL_S, POINT_MAP_SHARE * took))


async def contained(
    name: str, work: Callable[[], Awaitable[None]], restart_s: float = RESTART_S
) -> None:
    """Runs one drawing loop; should it fail, the 3D view loses that layer for a moment,
    never the hub: the mirror runs in the hub's task group, where an escaped exception
    would end the hub's other work with it."""
    while True:
        try:
            await work()
            return
        except Exception:
            log.exception("3D view: the %s layer failed; restarting it in %.0f s", name, restart_s)
            await asyncio.sleep(restart_s)  # a back-off, so a fault that repeats cannot spin
