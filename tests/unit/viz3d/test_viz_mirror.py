"""The hub's scene mirror, driven through the real bus and read back through the viser
server's own API: the fleet's changes reach the scene in batches at a bounded rate.
(The scans' layers it runs are tested in tests/unit/scans/test_scene_layer.py.)"""

from __future__ import annotations

import asyncio
import contextlib
import time

import numpy as np
import pytest

from backend.fleet.registry import FleetRegistry
from backend.realtime.bus import InProcessBus, Topic
from backend.viz3d.frame import SceneFrame
from backend.viz3d.mirror import SceneMirror
from backend.viz3d.scene import FleetScene
from backend.viz3d.server import VizServer
from tests.support.scenes import HOME, _node, _summary, until

INTERVAL_S = 0.1


@pytest.fixture
def scene(viz: VizServer) -> FleetScene:
    return FleetScene(viz.viser, SceneFrame(), trail_s=30.0)


def test_fifty_vehicles_at_a_high_rate_reach_the_scene_in_bounded_batches(
    viz: VizServer, scene: FleetScene
) -> None:
    asyncio.run(_fifty_vehicles(viz, scene))


async def _fifty_vehicles(viz: VizServer, scene: FleetScene) -> None:
    # No pytest-asyncio here: the test runs its own loop, and the mirror's task in it.
    bus = InProcessBus()
    mirror = SceneMirror(scene, bus, FleetRegistry(), INTERVAL_S)
    task = asyncio.create_task(mirror.run())
    try:
        await until(lambda: bus._subscriptions[Topic.VEHICLE_STATE], "the mirror subscribed")
        vehicles = [f"v{i:02d}" for i in range(50)]
        steps = 60
        started = time.monotonic()
        for step in range(steps):
            for i, vehicle in enumerate(vehicles):
                lat = HOME[0] + step * 1e-6
                lon = HOME[1] + i * 1e-4
                summary = _summary(vehicle, float(step), lat=lat, lon=lon, alt_msl=HOME[2] + 10)
                await bus.publish(Topic.VEHICLE_STATE, vehicle, summary)
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

        await until(newest_drawn, "every vehicle's newest position")
        elapsed = time.monotonic() - started
        # 3,000 changes arrived; the browser got at most one batch a period (and the first).
        assert mirror.scene.batches <= elapsed / INTERVAL_S + 2, (
            mirror.scene.batches,
            elapsed,
        )
        assert mirror.scene.batches < steps
    finally:
        task.cancel()
        with contextlib.suppress(asyncio.CancelledError):
            await task
