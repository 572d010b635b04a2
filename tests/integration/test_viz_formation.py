"""A running formation in the hub's 3D view, read off the view's own WebSocket: the hub's
formation service feeds the layer (backend/formation/scene_layer.py), its slot lines
and separation spheres appear while the formation runs and go when it is stopped."""

from __future__ import annotations

import time
from typing import Any

import pytest
from websockets.sync.client import ClientConnection, connect

from common.geodesy import LocalFrame
from gcs.launcher import LocalFleet
from tests.support.api import api_client
from tests.support.settling import take_off
from tests.support.watcher import FleetWatcher, ready
from tests.viz_wire import SUBPROTOCOL, scene_messages, viewer_camera

pytestmark = pytest.mark.integration

LEADER, FOLLOWERS = "sim_1", ("sim_2", "sim_3")
ALTITUDES = {LEADER: 8.0, "sim_2": 3.0, "sim_3": 2.0}  # apart in height while they join
MIN_SEPARATION_M = 2.0


def _request(frame: LocalFrame) -> dict[str, Any]:
    route = []
    for north, east in [(0, 0), (15, 0)]:
        lat, lon = frame.to_geo(east, north)
        route.append({"lat": lat, "lon": lon, "alt_m": ALTITUDES[LEADER]})
    return {
        "leader_id": LEADER,
        "route": route,
        "speed_ms": 1.0,
        "pause_s": 30.0,  # the leader holds at the start: nothing moves far
        "followers": [{"vehicle_id": f, "up": ALTITUDES[f] - ALTITUDES[LEADER]} for f in FOLLOWERS],
        "shape": "triangle",
        "spacing_m": 3.0,
        "min_separation_m": MIN_SEPARATION_M,
    }


class Scene:
    """The scene as one viewer's WebSocket tells it: nodes by name, newest message each."""

    def __init__(self, ws: ClientConnection) -> None:
        self.ws = ws
        self.nodes: dict[str, dict[str, Any]] = {}

    def wait_for(self, condition: Any, timeout_s: float, what: str) -> None:
        deadline = time.monotonic() + timeout_s
        while not condition(self.nodes):
            left = deadline - time.monotonic()
            if left <= 0:
                raise AssertionError(f"timed out after {timeout_s:g} s waiting for {what}")
            try:
                frame = self.ws.recv(timeout=left)
            except TimeoutError:
                continue
            if not isinstance(frame, bytes):
                continue
            for message in scene_messages(frame):
                name = message.get("name")
                if not isinstance(name, str):
                    continue
                if message["type"] == "RemoveSceneNodeMessage":
                    self.nodes.pop(name, None)
                elif "props" in message:
                    self.nodes[name] = message


def test_a_formation_is_drawn_in_3d_while_it_runs(
    settled_fleet: LocalFleet, fleet_admin_token: str
) -> None:
    base = settled_fleet.plan.hub_http
    auth = {"Authorization": f"Bearer {fleet_admin_token}"}
    url = base.replace("http://", "ws://") + "/viz"
    with (
        FleetWatcher(base, fleet_admin_token) as watcher,
        api_client(base, fleet_admin_token) as api,
        connect(url, subprotocols=[SUBPROTOCOL], additional_headers=auth) as ws,  # type: ignore[list-item]
    ):
        ws.send(viewer_camera())
        scene = Scene(ws)
        for vehicle, altitude in ALTITUDES.items():
            watcher.wait_until(ready(vehicle), 60, f"{vehicle} ready")
            take_off(api, watcher, vehicle, altitude, above=altitude / 2)
        for vehicle in ALTITUDES:  # a formation takes members that fly, by their autopilot
            watcher.wait_until(
                lambda v, n=vehicle: v[n]["state"]["landed_state"] in ("takeoff", "in_air"),
                10,
                f"{vehicle} in the air by its autopilot",
            )
        here = watcher.state(LEADER)
        answer = api.post("/api/v1/formations", json=_request(LocalFrame(here["lat"], here["lon"])))
        assert answer.status_code == 200, answer.text
        formation_id = answer.json()["id"]
        root = f"/formations/{formation_id}"
        spheres = [f"{root}/separation/{v}" for v in ALTITUDES]
        try:
            scene.wait_for(
                lambda nodes: f"{root}/links" in nodes and all(s in nodes for s in spheres),
                30,
                "the formation's lines and spheres",
            )
            assert scene.nodes[f"{root}/links"]["type"] == "LineSegmentsMessage"
            for sphere in spheres:
                assert scene.nodes[sphere]["props"]["radius"] == pytest.approx(1.0)
        finally:  # the members hold where they are; settled_fleet lands them
            assert api.post(f"/api/v1/formations/{formation_id}/stop").status_code == 200
        scene.wait_for(
            lambda nodes: not any(name.startswith(root) for name in nodes), 30, "them gone"
        )
