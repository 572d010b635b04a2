"""A flight controller that never answers: the command times out with a clear error."""

from __future__ import annotations

import subprocess
import time
from collections.abc import Callable, Iterator

import pytest

from tests.support.api import api_client
from tests.support.processes import agent_process
from tests.support.silent_fcu import SilentFlightController
from tests.support.watcher import FleetWatcher, connected

pytestmark = pytest.mark.integration


@pytest.fixture
def silent_agent(hub: str, enrol: Callable[[str], str]) -> Iterator[subprocess.Popen[bytes]]:
    with (
        SilentFlightController(system_id=7) as fcu,
        agent_process(hub, enrol("silent"), "silent", fcu.port) as agent,
    ):
        yield agent


def test_command_to_a_silent_flight_controller_times_out(
    hub: str, admin_token: str, silent_agent: subprocess.Popen[bytes]
) -> None:
    with FleetWatcher(hub, admin_token) as watcher:
        watcher.wait_until(connected("silent"), 30, "the silent vehicle to connect")
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
