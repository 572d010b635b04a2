"""The hub's scene mirror, driven through the real bus and scan service and read back
through the viser server's own API: batches at a bounded rate, and scans whose points
land on the simulator's obstacles in the scene's local frame."""

from __future__ import annotations

import asyncio
import contextlib
import math
import time
from array import array
from collections.abc import AsyncIterator
from contextlib import asynccontextmanager
from typing import Any

import numpy as np
import pytest
import sqlalchemy

from backend.fleet.registry import FleetRegistry
from backend.realtime.bus import InProcessBus, Topic
from backend.scans.service import ScanService
from backend.storage.scans import ScanRepository
from backend.viz3d.frame import SceneFrame, reframe
from backend.viz3d.mirror import SceneMirror
from backend.viz3d.scene import FleetScene
from backend.viz3d.server import VizServer
from common.geodesy import GeoPoint, LocalFrame
from protocol.scans import NO_RETURN, ScanFrame, ScanPose, encode_scan
from simulator.sensors.lidar import Lidar, LidarSpec, Pose
from simulator.world.obstacles import default_scene
from tests.support.scenes import HOME, _node, _summary

INTERVAL_S = 0.1
WORLD = default_scene()
# The simulator's world is metres east/north/up of the vehicle's home. The scene's
# origin is put elsewhere (as GCS_VIZ_ORIGIN may), so the test sees the points moved
# from the scans' site frame into the scene's, not merely passed through.
SITE = LocalFrame(*HOME)
SCENE_ORIGIN = SITE.from_enu(18.0, -12.0, 0.0)


@pytest.fixture
def scene(viz: VizServer) -> FleetScene:
    frame = SceneFrame(GeoPoint(SCENE_ORIGIN.lat, SCENE_ORIGIN.lon, SCENE_ORIGIN.alt))
    return FleetScene(viz.viser, frame, trail_s=30.0)


class Running:
    def __init__(self, bus: InProcessBus, scans: ScanService, mirror: SceneMirror) -> None:
        self.bus, self.scans, self.mirror = bus, scans, mirror


@asynccontextmanager
async def running(scene: FleetScene) -> AsyncIterator[Running]:
    """The mirror's task over a real bus and scan service (no pytest-asyncio here: each
    test runs its own loop)."""
    bus = InProcessBus()
    # The store is only written by the service's own run(), which is not started here.
    scans = ScanService(ScanRepository(sqlalchemy.create_engine("sqlite://")), bus, site=SITE)
    mirror = SceneMirror(scene, bus, FleetRegistry(), INTERVAL_S, scans=scans)
    task = asyncio.create_task(mirror.run())
    try:
        await _until(lambda: len(bus._subscriptions[Topic.SCANS]) == 1, "the mirror subscribed")
        yield Running(bus, scans, mirror)
    finally:
        task.cancel()
        with contextlib.suppress(asyncio.CancelledError):
            await task


async def _until(condition: Any, what: str, within: float = 10.0) -> Any:
    deadline = time.monotonic() + within
    while time.monotonic() < deadline:
        if result := condition():
            return result
        await asyncio.sleep(0.02)
    raise AssertionError(f"timed out waiting for {what}")


def _simulated_scan(east: float, north: float, up: float, yaw: float, roll: float) -> ScanFrame:
    """One turn of the simulator's LIDAR at a pose (metres of the site, radians), as the
    agent frames it: beam i clockwise from the nose, millimetres, 0 for no return."""
    spec = LidarSpec(noise_sigma_m=0.0, dropout=0.0)
    lidar = Lidar(WORLD, spec)
    turn = 1.0 / spec.rate_hz
    lidar.advance(Pose(0.0, east, north, up, roll, 0.0, yaw))
    beams = lidar.advance(Pose(turn - 1e-9, east, north, up, roll, 0.0, yaw))
    assert beams is not None
    assert len(beams.range_m) == spec.beams
    ranges = array("H", [NO_RETURN if r == 0 else round(r * 1000) for r in beams.range_m])
    where = SITE.from_enu(east, north, up)
    pose = ScanPose(where.lat, where.lon, where.alt, roll=roll, pitch=0.0, yaw=yaw)
    return ScanFrame(
        seq=1,
        sensor_time_us=0,
        utc_time=time.time(),
        duration_s=turn,
        angle_min=0.0,
        angle_increment=-2 * math.pi / spec.beams,
        range_max_m=spec.max_range_m,
        pose_start=pose,
        pose_end=pose,
        ranges=ranges,
    )


def test_scan_points_land_on_the_simulators_obstacles_in_the_local_frame(
    viz: VizServer, scene: FleetScene
) -> None:
    asyncio.run(_scan_points_land(viz, scene))


async def _scan_points_land(viz: VizServer, scene: FleetScene) -> None:
    async with running(scene) as hub:
        assert "scans" not in scene.layers_shown
        sensor_site = np.array([1.5, -2.0, 3.0])
        frame = _simulated_scan(*sensor_site, yaw=math.radians(35.0), roll=math.radians(4.0))
        await hub.scans.ingest("alpha", "s1", encode_scan(frame))

        cloud = await _until(lambda: _node(viz.viser, "/scans/alpha"), "the scan in the scene")
        shown = np.asarray(cloud.points, dtype=np.float64)
        returns = sum(1 for r in frame.ranges if r != NO_RETURN)
        assert returns > 300  # the yard's walls and masts, and the ground where it rolls
        assert len(shown) == returns
        scene_frame = scene.frame.local
        assert scene_frame is not None
        # In the scene's frame, the sensor is where the simulator put it...
        sensor_scene = reframe(sensor_site[None, :], SITE, scene_frame)[0]
        np.testing.assert_allclose(sensor_scene, sensor_site - (18.0, -12.0, 0.0), atol=0.01)
        # ...each point is as far from it as its beam measured (float16 on the wire)...
        measured = np.array([r / 1000 for r in frame.ranges if r != NO_RETURN])
        np.testing.assert_allclose(
            np.linalg.norm(shown - sensor_scene, axis=1), measured, atol=0.03, rtol=0
        )
        # ...and, taken back to the simulator's frame, on its true surfaces.
        in_world = reframe(shown, scene_frame, SITE)
        error = np.minimum(WORLD.distance_to_surface(in_world), np.abs(in_world[:, 2]))
        assert float(np.max(error)) < 0.03, float(np.max(error))
        assert "scans" in scene.layers_shown

        # The accumulated map and the obstacles found in it appear as their own layers.
        points = await _until(lambda: _node(viz.viser, "/point_map/all"), "the point map", 15)
        in_world = reframe(np.asarray(points.points, dtype=np.float64), scene_frame, SITE)
        error = np.minimum(WORLD.distance_to_surface(in_world), np.abs(in_world[:, 2]))
        assert float(np.percentile(error, 99)) < 0.15  # voxel centres, 10 cm voxels
        # (the boxes follow the points in the same batch: wait for the whole of it)
        await _until(lambda: "obstacles" in scene.layers_shown, "the obstacles layer")
        assert "point_map" in scene.layers_shown
        boxes = [
            handle
            for name, handle in viz.viser.scene._handle_from_node_name.items()
            if name.startswith("/obstacles/")
        ]
        assert boxes
        # The building east of home (centre 9, 2 in the simulator's frame) is one of them.
        centres = reframe(np.array([np.asarray(b.position) for b in boxes]), scene_frame, SITE)
        assert np.min(np.linalg.norm(centres[:, :2] - (9.0, 2.0), axis=1)) < 2.5


def test_fifty_vehicles_at_a_high_rate_reach_the_scene_in_bounded_batches(
    viz: VizServer, scene: FleetScene
) -> None:
    asyncio.run(_fifty_vehicles(viz, scene))


async def _fifty_vehicles(viz: VizServer, scene: FleetScene) -> None:
    async with running(scene) as hub:
        vehicles = [f"v{i:02d}" for i in range(50)]
        steps = 60
        started = time.monotonic()
        for step in range(steps):
            for i, vehicle in enumerate(vehicles):
                lat = HOME[0] + step * 1e-6
                lon = HOME[1] + i * 1e-4
                summary = _summary(vehicle, float(step), lat=lat, lon=lon, alt_msl=HOME[2] + 10)
                await hub.bus.publish(Topic.VEHICLE_STATE, vehicle, summary)
            await asyncio.sleep(0.01)  # 50 vehicles at up to 100 Hz: 5,000 changes a second
        local = scene.frame.local
        assert local is not None

        def newest_drawn() -> bool:
            for i, vehicle in enumerate(vehicles):
                node = _node(viz.viser, f"/vehicles/{vehicle}")
                want = local.to_enu(HOME[0] + (steps - 1) * 1e-6, HOME[1] + i * 1e-4, HOME[2] + 10)
                if node is None or not np.allclose(node.position, want, atol=1e-3):
                    return False
            return True

        await _until(newest_drawn, "every vehicle's newest position")
        elapsed = time.monotonic() - started
        # 3,000 changes arrived; the browser got at most one batch a period (and the first).
        assert hub.mirror.scene.batches <= elapsed / INTERVAL_S + 2, (
            hub.mirror.scene.batches,
            elapsed,
        )
        assert hub.mirror.scene.batches < steps
