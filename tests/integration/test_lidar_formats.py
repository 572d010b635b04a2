"""`gcs demo --lidar FORMAT` end to end, one format per manufacturer: the simulator speaks
the sensor's wire format over TCP, the agent's parser for the paired model reads it (its
start commands, the sensor's answers, the packets), and the hub places the points on the
obstacles; the parser's counts reach the hub's scan diagnostics. Real processes on
loopback."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import httpx
import numpy as np
import pytest

from common.geodesy import LocalFrame
from gcs.demo_lidars import DEMO_LIDARS
from simulator.world.obstacles import default_scene
from tests.support.api import access_token
from tests.support.processes import running_fleet
from tests.support.waiting import poll_until

pytestmark = pytest.mark.integration

WORLD = default_scene()


@pytest.mark.parametrize("lidar", ["rplidar-express", "ydlidar-x4", "ld06"])
def test_the_demos_lidar_reaches_the_hub_through_the_real_parser(
    tmp_path: Path, lidar: str
) -> None:
    with running_fleet(tmp_path, vehicles=1, speedup=1.0, lidars=True, lidar=lidar) as fleet:
        base, vehicle = fleet.plan.hub_http, fleet.vehicle_id(0)
        token = access_token(base, "admin", fleet.plan.admin_password)
        headers = {"Authorization": f"Bearer {token}"}
        site = LocalFrame(*fleet.plan.vehicle_home(0))

        def latest() -> dict[str, Any] | None:
            answer = httpx.get(f"{base}/api/v1/vehicles/{vehicle}/scans/latest", headers=headers)
            return answer.json() if answer.status_code == 200 else None

        scan = poll_until(latest, 60, f"a {lidar} scan at the hub")
        assert scan is not None
        enu = np.array([site.to_enu(*p) for p in scan["geodetic"]])
        assert len(enu) > 300  # the default yard, at 0.5 degree
        errors = np.minimum(WORLD.distance_to_surface(enu), np.abs(enu[:, 2]))
        assert np.median(errors) <= 0.05, np.median(errors)
        assert np.mean(errors <= 0.20) >= 0.97, np.percentile(errors, 97)

        # The agent's parser reports its counts to the hub's scan diagnostics.
        def reported() -> dict[str, Any] | None:
            body: dict[str, Any] = httpx.get(
                f"{base}/api/v1/vehicles/{vehicle}/scans/diagnostics", headers=headers
            ).json()
            return body if body["source_counts"].get("points", 0) > 1000 else None

        diagnostics = poll_until(reported, 30, "the parser's counts in the diagnostics")
        assert diagnostics is not None
        assert diagnostics["rejected"] == {}
        assert diagnostics["source"] == DEMO_LIDARS[lidar].model
        counts = diagnostics["source_counts"]
        assert counts["packets"] > 0
        # a clean line drops nothing (a reconnect's first bytes may begin mid-packet)
        dropped = {k: v for k, v in counts.items() if k.startswith("dropped_")}
        assert sum(dropped.values()) <= 100, dropped
