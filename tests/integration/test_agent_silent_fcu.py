"""A flight controller that never answers: the command times out with a clear error."""

from __future__ import annotations

import os
import socket
import subprocess
import sys
import threading
import time
from collections.abc import Callable, Iterator

import pytest
from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from tests.helpers import FleetWatcher, api_client

pytestmark = pytest.mark.integration


class SilentFlightController:
    """A real MAVLink peer on TCP that sends heartbeats and ignores every command."""

    def __init__(self) -> None:
        self._server = socket.create_server(("127.0.0.1", 0))
        self.port = self._server.getsockname()[1]
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._serve, daemon=True)

    def __enter__(self) -> SilentFlightController:
        self._thread.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self._stop.set()
        self._server.close()
        self._thread.join(5)

    def _serve(self) -> None:
        mav = mavlink2.MAVLink(None, srcSystem=7, srcComponent=1)
        heartbeat = mavlink2.MAVLink_heartbeat_message(
            mavlink2.MAV_TYPE_QUADROTOR,
            mavlink2.MAV_AUTOPILOT_ARDUPILOTMEGA,
            mavlink2.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED,
            4,
            mavlink2.MAV_STATE_STANDBY,
            3,
        )
        with self._server.accept()[0] as peer:
            while not self._stop.wait(0.2):  # a 5 Hz heartbeat is the whole behaviour
                peer.sendall(heartbeat.pack(mav))


@pytest.fixture
def silent_agent(hub: str, enrol: Callable[[str], str]) -> Iterator[subprocess.Popen[bytes]]:
    with SilentFlightController() as fcu:
        agent = subprocess.Popen(
            [
                sys.executable,
                "-m",
                "gcs",
                "agent",
                "--fcu",
                f"tcp:127.0.0.1:{fcu.port}",
                "--hub",
                hub.replace("http://", "ws://"),
                "--vehicle-id",
                "silent",
            ],
            env={**os.environ, "GCS_AGENT_TOKEN": enrol("silent")},
        )
        try:
            yield agent
        finally:
            agent.terminate()
            agent.wait(10)


def test_command_to_a_silent_flight_controller_times_out(
    hub: str, admin_token: str, silent_agent: subprocess.Popen[bytes]
) -> None:
    with FleetWatcher(hub, admin_token) as watcher:
        watcher.wait_until(
            lambda v: "silent" in v and v["silent"]["connected"],
            30,
            "the silent vehicle to connect",
        )
    with api_client(hub, admin_token, timeout_s=60) as api:
        started = time.monotonic()
        # Landing is never held back by safety rails, so it really goes to the vehicle.
        response = api.post("/api/v1/vehicles/silent/commands", json={"name": "land"})
        elapsed = time.monotonic() - started
    assert response.status_code == 504
    detail = response.json()["detail"]
    assert "MAV_CMD_NAV_LAND" in detail
    assert "no COMMAND_ACK" in detail
    assert elapsed < 15, "the agent's retries are bounded, not a hang"
    assert silent_agent.poll() is None, "the agent survives the timeout"
