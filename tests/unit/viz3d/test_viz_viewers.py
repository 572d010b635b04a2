"""The map and the 3D view select the same vehicle: driven through viser's server with
real viewers connected over its WebSocket, reading what each viewer is sent."""

from __future__ import annotations

import json
import re
import threading

import numpy as np
import pytest
from websockets.sync.client import ClientConnection

from backend.errors import Conflict, NotFound
from backend.viz3d.frame import SceneFrame
from backend.viz3d.scene import FleetScene
from backend.viz3d.server import VizServer
from backend.viz3d.viewers import MAX_VIEW_DISTANCE_M, Viewers
from tests.support.scenes import HOME, _summary
from tests.support.waiting import poll_until
from tests.viz_wire import scene_messages, scene_socket, viewer_camera

POSTED = re.compile(r"window\.parent\.postMessage\((\{.*?\}), window\.location\.origin\)")


class Viewer:
    """A browser's viewer: it sends its camera, then reads everything it is sent."""

    def __init__(self, viz: VizServer) -> None:
        self.ws: ClientConnection = scene_socket(viz)
        self.ws.send(viewer_camera())
        self.posted: list[dict[str, object]] = []
        threading.Thread(target=self._read, daemon=True).start()

    def _read(self) -> None:
        for frame in self.ws:
            if isinstance(frame, bytes):
                for message in scene_messages(frame):
                    if message["type"] == "RunJavascriptMessage":
                        found = POSTED.search(message["source"])
                        if found:
                            self.posted.append(json.loads(found.group(1)))

    def said(self, kind: str) -> dict[str, object]:
        return poll_until(
            lambda: next((m for m in self.posted if m["type"] == kind), None), 10, kind
        )


def test_each_viewer_learns_its_id_and_secret_and_turns_to_the_maps_selection(
    viz: VizServer,
) -> None:
    scene = FleetScene(viz.viser, SceneFrame(), trail_s=30.0)
    viewers = Viewers(viz.viser, scene)
    north = (HOME[0] + 0.0009, HOME[1], HOME[2] + 20)  # ~100 m north, 20 m up
    scene.apply([_summary("alpha", 1.0, lat=north[0], lon=north[1], alt_msl=north[2])])
    first, second = Viewer(viz), Viewer(viz)
    try:
        hello = first.said("gcs-viz-viewer")
        other = second.said("gcs-viz-viewer")
        assert hello["viewer"] != other["viewer"]
        assert hello["secret"] != other["secret"]
        viewer_id, secret = int(hello["viewer"]), str(hello["secret"])  # type: ignore[call-overload]

        with pytest.raises(NotFound):
            viewers.select(viewer_id, str(other["secret"]), "alpha")  # another page's secret
        with pytest.raises(Conflict):
            viewers.select(viewer_id, secret, "nowhere")  # no position in the view
        looks_at = viewers.select(viewer_id, secret, "alpha")

        target = scene.vehicle_position("alpha")
        assert target is not None
        np.testing.assert_allclose(looks_at, target, atol=1e-6)
        camera = viz.viser.get_clients()[viewer_id].camera
        np.testing.assert_allclose(camera.look_at, target, atol=1e-6)
        assert np.linalg.norm(camera.position - camera.look_at) <= MAX_VIEW_DISTANCE_M + 1e-6
        # The other viewer's camera did not move.
        untouched = viz.viser.get_clients()[int(other["viewer"])].camera  # type: ignore[call-overload]
        np.testing.assert_allclose(untouched.look_at, (0, 0, 0), atol=1e-6)

        # It follows the vehicle as it moves on.
        further = (north[0] + 0.0009, north[1], north[2])
        scene.apply([_summary("alpha", 2.0, lat=further[0], lon=further[1], alt_msl=further[2])])
        np.testing.assert_allclose(camera.look_at, scene.vehicle_position("alpha"), atol=1e-6)

        # A click on the vehicle in 3D tells the clicking viewer's dashboard only.
        scene._clicked("alpha", viz.viser.get_clients()[viewer_id])
        assert first.said("gcs-viz-select")["vehicle"] == "alpha"
        assert not [m for m in second.posted if m["type"] == "gcs-viz-select"]
    finally:
        first.ws.close()
        second.ws.close()
    poll_until(lambda: len(viewers) == 0, 10, "the viewers gone")
