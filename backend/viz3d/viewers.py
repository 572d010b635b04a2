"""The map and the 3D view select the same vehicle.

viser's client runs in an iframe of the dashboard, on the hub's own origin. When a
viewer connects, the hub runs a line in its page that tells the dashboard around it the
viewer's id and a secret that only that page sees. The dashboard then sends each
selection to the hub with both (``POST /api/v1/viz/viewers/{viewer}/selection``), and
the hub turns that viewer's camera to the vehicle; without the secret nobody can turn
another operator's camera. A click on a vehicle in 3D runs a line in the clicking
viewer's page that tells its own dashboard, which selects the vehicle on the map.
"""

from __future__ import annotations

import json
import logging
import secrets
from dataclasses import dataclass

import numpy as np
import viser
from viser import _messages as viser_messages

from backend.errors import Conflict, NotFound
from backend.viz3d.scene import FleetScene

log = logging.getLogger(__name__)

# The camera keeps its direction to the vehicle, at no more than this distance.
MAX_VIEW_DISTANCE_M = 40.0
MIN_VIEW_DISTANCE_M = 8.0


@dataclass(frozen=True)
class Viewer:
    client: viser.ClientHandle
    secret: str


def _tell_dashboard(client: viser.ClientHandle, message: dict[str, object]) -> None:
    """Post ``message`` from the viewer's page to the dashboard that frames it (same
    origin only). viser runs the line with ``new Function``, which its page's policy
    allows for viser's own code (backend.viz3d.server.page_policy)."""
    source = (
        "if (window.parent !== window) "
        f"window.parent.postMessage({json.dumps(message)}, window.location.origin);"
    )
    client.gui._websock_interface.queue_message(viser_messages.RunJavascriptMessage(source=source))


class Viewers:
    """The connected viewers of the 3D view, and the selection they share with the map."""

    def __init__(self, server: viser.ViserServer, scene: FleetScene) -> None:
        self._scene = scene
        self._viewers: dict[int, Viewer] = {}
        server.on_client_connect(self._connected)
        server.on_client_disconnect(self._disconnected)
        scene.on_vehicle_click = self._clicked

    def __len__(self) -> int:
        return len(self._viewers)

    def select(self, viewer_id: int, secret: str, vehicle_id: str) -> tuple[float, ...]:
        """Turn this viewer's camera to the vehicle; where it now looks (east, north, up)."""
        viewer = self._viewers.get(viewer_id)
        # One answer for an unknown viewer and a wrong secret: ids are small numbers.
        if viewer is None or not secrets.compare_digest(viewer.secret, secret):
            raise NotFound(f"no 3D viewer {viewer_id} with that secret")
        target = self._scene.vehicle_position(vehicle_id)
        if target is None:
            raise Conflict(f"{vehicle_id} is not in the 3D view (no position yet)")
        camera = viewer.client.camera
        offset = np.asarray(camera.position, dtype=np.float64) - np.asarray(camera.look_at)
        distance = float(np.linalg.norm(offset))
        if distance < 1e-6:
            offset, distance = np.array([0.0, -1.0, 0.6]), float(np.linalg.norm([0, -1, 0.6]))
        offset *= np.clip(distance, MIN_VIEW_DISTANCE_M, MAX_VIEW_DISTANCE_M) / distance
        with viewer.client.atomic():  # position first: viser moves look_at along with it
            camera.position = target + offset
            camera.look_at = target
        # Then it follows the vehicle from there, as the panel's "Follow" does.
        self._scene.follow(viewer_id, vehicle_id)
        return tuple(float(value) for value in target)

    def _connected(self, client: viser.ClientHandle) -> None:
        viewer = Viewer(client=client, secret=secrets.token_urlsafe(24))
        self._viewers[client.client_id] = viewer
        _tell_dashboard(
            client, {"type": "gcs-viz-viewer", "viewer": client.client_id, "secret": viewer.secret}
        )

    def _disconnected(self, client: viser.ClientHandle) -> None:
        self._viewers.pop(client.client_id, None)

    def _clicked(self, vehicle_id: str, client: viser.ClientHandle) -> None:
        _tell_dashboard(client, {"type": "gcs-viz-select", "vehicle": vehicle_id})
