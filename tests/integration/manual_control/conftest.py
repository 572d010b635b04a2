"""One fleet for the whole package, as the single module before it had: an ArduPilot
copter hovering at 10 m in GUIDED and a PX4 copter on the ground beside it, at real time.

The modules run in the order of their names and their tests in the order written, which
is the order these flights need: the lease and stick tests fly the hovering copter first,
`test_missions_px4_and_restart.py` comes after, and its last test restarts the hub."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import pytest

from gcs.launcher import LocalFleet
from tests.support.api import access_token, api_client
from tests.support.manual_flight import OPERATOR_PASSWORD, PX4_VEHICLE
from tests.support.pilots import VEHICLE
from tests.support.processes import running_fleet
from tests.support.settling import take_off
from tests.support.watcher import FleetWatcher, ready


@pytest.fixture(scope="package")
def flying(tmp_path_factory: pytest.TempPathFactory) -> Iterator[tuple[LocalFleet, str]]:
    """One copter at 10 m in GUIDED; a PX4 copter on the ground beside it."""
    data_dir: Path = tmp_path_factory.mktemp("manual")
    with running_fleet(data_dir, vehicles=2, speedup=1.0, autopilots=("ardupilot", "px4")) as fleet:
        base = fleet.plan.hub_http
        token = access_token(base, "admin", fleet.plan.admin_password)
        with FleetWatcher(base, token) as watcher, api_client(base, token) as api:
            watcher.wait_until(ready(VEHICLE), 60, f"{VEHICLE} ready")
            watcher.wait_until(ready(PX4_VEHICLE), 60, f"{PX4_VEHICLE} ready")
            take_off(api, watcher, VEHICLE, 10.0, above=9.0)
            created = api.post(
                "/api/v1/users",
                json={"username": "pilot", "password": OPERATOR_PASSWORD, "role": "operator"},
            )
            assert created.status_code in (200, 201), created.text
        yield fleet, token
