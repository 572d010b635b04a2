"""The scans in the 3D view: each vehicle's latest scan, and the site's point map with the
obstacles found in it, each a layer of the scene that appears with its first data.

Scans are taken as the mirror takes vehicles (each vehicle's newest, at most once per
interval), in the vehicle's colour; the accumulated point map, which only grows slowly,
less often. Both are in the scans' site frame (``ScanService.site``) and are moved into
the scene's by one rigid transform. The layers plug into the 3D view's mirror as
``SceneLayer``s (``scan_scene_layers``, put on ``Hub.scene_layers`` by app.py).
"""

from __future__ import annotations

import asyncio
import time
from collections.abc import Awaitable, Callable, Sequence

import numpy as np
import numpy.typing as npt
import viser

from backend.realtime.bus import Bus, LatestSubscription, Topic
from backend.scans.pointmap import Array, MapObstacle, find_obstacles
from backend.scans.service import ScanDelivery, ScanService
from backend.viz3d.colours import rgb, vehicle_colour
from backend.viz3d.frame import HomeAltitude, reframe
from backend.viz3d.mirror import SceneLayer
from backend.viz3d.scene import OBSTACLES, POINT_MAP, SCANS, FleetScene
from common.geodesy import LocalFrame

POINT_MAP_COLOUR = (150, 150, 150)
OBSTACLE_COLOUR = (255, 80, 0)
MAX_OBSTACLES = 200
# The point map is redrawn at most this often, and only its newest voxels: it is the
# scene's heaviest message, and it changes little from one second to the next.
POINT_MAP_INTERVAL_S = 2.0
POINT_MAP_MAX_POINTS = 100_000
POINT_MAP_SHARE = 10.0


class ScanLayer:
    """What the scans drew in one scene (the obstacles' boxes, replaced at each redraw)."""

    def __init__(self, scene: FleetScene) -> None:
        self.scene = scene
        self._obstacles: list[viser.BoxHandle] = []

    def show_scan(
        self, vehicle_id: str, points: npt.NDArray[np.floating], site: LocalFrame
    ) -> bool:
        """A vehicle's latest scan: its world points as the scans feature placed them
        (``backend.scans.points``, each beam from the pose of its instant) in the site's
        frame, moved into the scene's, in the vehicle's colour. False, and nothing drawn,
        while the scene has no origin yet."""
        scene_frame = self.scene.frame.local
        if scene_frame is None:
            return False
        local = reframe(points, site, scene_frame)
        self.scene.show_points(SCANS, vehicle_id, local, rgb(vehicle_colour(vehicle_id)))
        return True

    def show_point_map(
        self, points: npt.NDArray[np.floating], obstacles: Sequence[MapObstacle], site: LocalFrame
    ) -> bool:
        """The site's accumulated point map and the obstacles found in it, both in the
        site's frame (``site``), moved into the scene's. False while it has no origin."""
        local = self.scene.frame.local
        if local is None:
            return False
        scene = self.scene
        with scene.batch():
            if len(points):
                scene.show_points(POINT_MAP, "all", reframe(points, site, local), POINT_MAP_COLOUR)
            for handle in self._obstacles:
                handle.remove()
            self._obstacles = []
            # The largest first, and a bounded number: one box is one scene message.
            for obstacle in sorted(obstacles, key=lambda o: -o.voxels)[:MAX_OBSTACLES]:
                low = (obstacle.east_min, obstacle.north_min, obstacle.up_min)
                high = (obstacle.east_max, obstacle.north_max, obstacle.up_max)
                corners = reframe(np.array([low, high]), site, local)
                self._obstacles.append(
                    scene.server.scene.add_box(
                        f"/{OBSTACLES.key}/{obstacle.id}",
                        color=OBSTACLE_COLOUR,
                        dimensions=tuple(np.abs(corners[1] - corners[0]).tolist()),
                        wireframe=True,
                        position=corners.mean(axis=0),
                    )
                )
            if obstacles:
                scene.show_layer(OBSTACLES)
        return True

    async def follow_scans(self, bus: Bus, scans: ScanService, interval_s: float) -> None:
        """Draw each vehicle's newest scan, at most every ``interval_s``."""
        updates = LatestSubscription()
        bus.subscribe(Topic.SCANS, updates)
        try:
            while True:
                deliveries: list[ScanDelivery] = await updates.drain()
                await asyncio.to_thread(self._show_scans, scans, deliveries)
                await asyncio.sleep(interval_s)
        finally:
            bus.unsubscribe(Topic.SCANS, updates)

    def _show_scans(self, scans: ScanService, deliveries: list[ScanDelivery]) -> None:
        site = scans.site
        if site is None:
            return
        with self.scene.batch():
            for delivery in deliveries:
                # The service's newest scan of the vehicle, its points already placed
                # (at least as new as the delivery that woke us).
                if (latest := scans.latest.get(delivery.vehicle_id)) is not None:
                    self.show_scan(delivery.vehicle_id, latest.points.enu, site)

    def _show_point_map(self, points: Array, voxel_m: float, site: LocalFrame) -> None:
        self.show_point_map(points, find_obstacles(points, voxel_m), site)

    async def follow_point_map(self, scans: ScanService) -> None:
        """Redraw the point map and its obstacles when it has changed, at a bounded share
        of a core."""
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


def scan_scene_layers(scans: ScanService, bus: Bus) -> list[tuple[str, SceneLayer]]:
    """The scans' layers of the 3D view's mirror: the latest scans, and the point map with
    its obstacles (each loop draws with its own ``ScanLayer``: only the map's keeps boxes)."""

    def latest(
        scene: FleetScene, home_alt: HomeAltitude, interval_s: float
    ) -> Callable[[], Awaitable[None]]:
        layer = ScanLayer(scene)
        return lambda: layer.follow_scans(bus, scans, interval_s)

    def point_map(
        scene: FleetScene, home_alt: HomeAltitude, interval_s: float
    ) -> Callable[[], Awaitable[None]]:
        layer = ScanLayer(scene)
        return lambda: layer.follow_point_map(scans)

    return [("scans", latest), ("point map", point_map)]
