"""Keeps the 3D scene in step with the fleet, in batches at a bounded rate.

Vehicle changes arrive on the bus as they happen (50 vehicles at 10 Hz is 500 a second).
The mirror takes them newest-wins per vehicle, and at most once per period applies what
has changed as one atomic scene update: the browser gets a bounded number of updates a
second whatever the fleet's size and rate, and never a stale state before a newer one.
Surveys' lanes and mosaics have a layer module each (backend/survey/viz_layer.py,
backend/imagery/mosaic/viz_layer.py), and a feature package may bring its own
(``SceneLayer``: the formation's, backend/formation/scene_layer.py, and the scans' and point
map's, backend/scans/scene_layer.py); the mirror runs them beside its own work.
"""

from __future__ import annotations

import asyncio
import logging
from collections.abc import Awaitable, Callable, Iterable, Iterator

from backend.errors import VehicleNotFound
from backend.fleet.registry import FleetRegistry
from backend.imagery.mosaic.service import MosaicService
from backend.imagery.mosaic.viz_layer import MosaicLayer
from backend.realtime.bus import Bus, LatestSubscription, Topic
from backend.survey.service import SurveyService
from backend.survey.viz_layer import SurveyLanes
from backend.viz3d.frame import HomeAltitude
from backend.viz3d.scene import FleetScene

log = logging.getLogger(__name__)

RESTART_S = 5.0  # before a failed layer's loop is started again

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
