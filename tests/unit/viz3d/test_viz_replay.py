"""A stored flight replayed in the 3D view: each viewer's own panel and ghost, driven
through the viser server's API with real viewers connected over its WebSocket."""

from __future__ import annotations

import threading
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest
from sqlalchemy import Engine
from sqlalchemy.orm import Session
from websockets.sync.client import ClientConnection

from backend.storage.database import make_engine, migrate
from backend.storage.logbook import Logbook
from backend.storage.models import FlightRow, TelemetryRow, VehicleRow
from backend.viz3d.frame import SceneFrame
from backend.viz3d.replay import NONE, FlightReplay, ReplayPanels, flight_label
from backend.viz3d.server import VizServer
from common.geodesy import GeoPoint, LocalFrame
from tests.support.waiting import poll_until
from tests.viz_wire import scene_socket, viewer_camera

HOME = (47.397742, 8.545594, 488.0)
START = 1_800_000_000.0
SAMPLES = 50  # one a second, flying north at 2 m/s and climbing 0.2 m/s


def _position(second: int) -> tuple[float, float, float]:
    return HOME[0] + second * 2.0 / 111_195, HOME[1], HOME[2] + second * 0.2


@pytest.fixture
def engine(tmp_path: Path) -> Iterator[Engine]:
    created = make_engine(f"sqlite:///{tmp_path}/store.sqlite3")
    migrate(created)
    with Session(created) as session:
        session.add(
            VehicleRow(
                id="alpha", autopilot="ardupilot", vehicle_type="quadrotor", system_id=1,
                first_seen=START, last_seen=START + SAMPLES,
            )
        )  # fmt: skip
        session.flush()  # the vehicle first: the samples and the flight refer to it
        for second in range(SAMPLES):
            lat, lon, alt = _position(second)
            session.add(
                TelemetryRow(
                    vehicle_id="alpha", stream_id="s", seq=second, time=START + second,
                    mode="AUTO", armed=True, lat=lat, lon=lon, alt_msl=alt,
                    alt_rel=alt - HOME[2], heading_deg=0.0, gps_fix=3,
                )
            )  # fmt: skip
        session.add(
            FlightRow(
                vehicle_id="alpha", start_time=START, end_time=START + SAMPLES - 1,
                duration_s=SAMPLES - 1.0,
            )
        )  # fmt: skip
        session.commit()
    yield created
    created.dispose()


def _viewer(
    viz: VizServer, panels: ReplayPanels, seen: int
) -> tuple[ClientConnection, FlightReplay]:
    """A viewer connected over viser's WebSocket, and the replay panel it was given."""
    ws = scene_socket(viz)
    ws.send(viewer_camera())
    # It reads what it is sent, as a browser does (an unread socket makes close() wait).
    threading.Thread(target=lambda: [None for _ in ws], daemon=True).start()
    poll_until(lambda: len(panels.by_client) > seen, 10, "the viewer's replay panel")
    newest = max(panels.by_client)
    return ws, panels.by_client[newest]


def test_a_viewer_scrubs_a_stored_flight_and_another_viewer_is_left_alone(
    viz: VizServer, engine: Engine
) -> None:
    frame = SceneFrame(GeoPoint(HOME[0], HOME[1], HOME[2]))
    truth = LocalFrame(*HOME)
    panels = ReplayPanels(viz.viser, frame, Logbook(engine))
    first_ws, first = _viewer(viz, panels, 0)
    second_ws, second = _viewer(viz, panels, 1)
    try:
        [flight] = Logbook(engine).flights(None, None, 5)
        label = flight_label(flight)
        assert first.flight_choice.options == (NONE, label)
        first.flight_choice.value = label  # type: ignore[misc]  # as the viewer picks it

        track = first.track
        assert track is not None
        assert len(track.times) == SAMPLES
        assert first.time_slider.max == pytest.approx(SAMPLES - 1)
        # The ghost stands where the log had the vehicle, to the millimetre.
        for second_into in (0, 17, SAMPLES - 1):
            first.time_slider.value = float(second_into)  # type: ignore[misc]
            ghost = first._ghost
            assert ghost is not None
            np.testing.assert_allclose(
                ghost.position, truth.to_enu(*_position(second_into)), atol=1e-3
            )
        # Between two samples it shows the older one, never an invented point.
        first.time_slider.value = 17.6  # type: ignore[misc]
        np.testing.assert_allclose(first._ghost.position, truth.to_enu(*_position(17)), atol=1e-3)  # type: ignore[union-attr]
        # The other viewer has no replay drawn: the ghost lives in its picker's scene only.
        assert second.track is None
        assert second._ghost is None

        # Played at 30x, the ghost reaches the flight's end and the button is Play again.
        first.speed.value = "30x"  # type: ignore[misc]
        first.time_slider.value = 0.0  # type: ignore[misc]
        first.toggle_play()
        poll_until(lambda: first.time_slider.value >= SAMPLES - 1, 20, "the replay's end")
        poll_until(lambda: first.play_button.label == "Play", 5, "the replay to stop")
        np.testing.assert_allclose(
            first._ghost.position, truth.to_enu(*_position(SAMPLES - 1)), atol=1e-3
        )  # type: ignore[union-attr]

        # Back to none: the track and ghost go.
        first.flight_choice.value = NONE  # type: ignore[misc]
        assert first.track is None
        assert first._ghost is None
    finally:
        first_ws.close()
        second_ws.close()
    poll_until(lambda: not panels.by_client, 10, "the viewers' panels dropped")
