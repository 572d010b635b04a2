from __future__ import annotations

import os
import shutil
from collections.abc import Callable, Iterator
from contextlib import ExitStack, contextmanager
from pathlib import Path

import httpx
import pytest
from sqlalchemy import Engine

from backend.storage.database import make_engine
from gcs.launcher import LocalFleet
from tests.support.api import access_token, api_client
from tests.support.hub_server import running_hub
from tests.support.hubs import ADMIN_PASSWORD, hub_settings, migrated_template
from tests.support.postgres import POSTGRES_ADDRESS, scratch_postgres
from tests.support.processes import running_fleet
from tests.support.settling import settle_fleet
from tests.support.waiting import poll_until

# imported from here by many test modules
__all__ = ["ADMIN_PASSWORD", "POSTGRES_ADDRESS", "hub_settings", "scratch_postgres"]

# The slow-test budget: an unmarked test over 20 s fails (tests/support/budget.py); every
# run ends with each folder's setup and call times (tests/support/phase_times.py).
pytest_plugins = ["tests.support.budget", "tests.support.phase_times"]

# Fast enough that a take-off and landing take seconds, slow enough that the
# 10 Hz telemetry still samples the climb finely.
FLEET_SPEEDUP = 5.0
FLEET_BATTERY_DRAIN = 0.1


@pytest.fixture
def hub(tmp_path: Path) -> Iterator[str]:
    """An in-process hub on SQLite in a temporary folder; yields its base URL."""
    with running_hub(hub_settings(tmp_path)) as base_url:
        yield base_url


@contextmanager
def _environment(**values: str) -> Iterator[None]:
    """Set environment variables for the processes started inside; restored after."""
    saved = {name: os.environ.get(name) for name in values}
    os.environ.update(values)
    try:
        yield
    finally:
        for name, value in saved.items():
            if value is None:
                os.environ.pop(name, None)
            else:
                os.environ[name] = value


@pytest.fixture(scope="session")
def fleet(tmp_path_factory: pytest.TempPathFactory) -> Iterator[LocalFleet]:
    """Hub, three simulators and three agents as real processes on loopback."""
    # Every test shares the admin's budget of requests that reach a vehicle on this hub;
    # at the default 20 a second, back-to-back tests would meet each other's 429s (the
    # limit's own tests run on hubs of their own).
    with ExitStack() as stack:
        with _environment(GCS_COMMANDS_PER_SECOND="1000"):  # for the processes it starts
            local_fleet = stack.enter_context(
                running_fleet(tmp_path_factory.mktemp("fleet"), vehicles=3, speedup=FLEET_SPEEDUP)
            )
        token = access_token(local_fleet.plan.hub_http, "admin", local_fleet.plan.admin_password)
        with api_client(local_fleet.plan.hub_http, token) as api:
            for index in range(local_fleet.plan.vehicles):
                # The whole suite flies these three for many sim-minutes; a full pack at
                # the real rate runs below the 30 % launch rail before the last tests
                # take off. Drawing a tenth keeps the battery moving (flights still use
                # some) without making the suite's order matter.
                vehicle = f"sim_{index + 1}"
                poll_until(
                    lambda vehicle=vehicle: (
                        api.put(
                            f"/api/v1/vehicles/{vehicle}/params/SIM_BATT_DRAIN",
                            json={"value": FLEET_BATTERY_DRAIN},
                        ).status_code
                        == 200
                    ),
                    60,
                    f"{vehicle} drawing its pack at {FLEET_BATTERY_DRAIN} of the rate",
                )
        yield local_fleet


@pytest.fixture
def admin_token(hub: str) -> str:
    return access_token(hub, "admin", ADMIN_PASSWORD)


@pytest.fixture
def admin_api(hub: str, admin_token: str) -> Iterator[httpx.Client]:
    with api_client(hub, admin_token) as client:
        yield client


@pytest.fixture
def enrol(admin_api: httpx.Client) -> Callable[[str], str]:
    """Enrol a vehicle through the admin API; returns its agent token."""

    def enrol_vehicle(vehicle_id: str) -> str:
        response = admin_api.post(f"/api/v1/vehicles/{vehicle_id}/agent-tokens")
        assert response.status_code == 201, response.text
        token: str = response.json()["token"]
        return token

    return enrol_vehicle


@pytest.fixture(scope="session")
def fleet_admin_token(fleet: LocalFleet) -> str:
    return access_token(fleet.plan.hub_http, "admin", fleet.plan.admin_password)


@pytest.fixture
def settled_fleet(fleet: LocalFleet, fleet_admin_token: str) -> Iterator[LocalFleet]:
    """The shared fleet in a known state (see `settle_fleet`: landed, disarmed, no survey
    or lease, a pack to fly on) before the test, and again after it, so that a test that
    flies leaves the fleet as it found it for the tests after it."""
    vehicles = [fleet.vehicle_id(index) for index in range(fleet.plan.vehicles)]
    settle_fleet(fleet.plan.hub_http, fleet_admin_token, vehicles)
    yield fleet
    settle_fleet(fleet.plan.hub_http, fleet_admin_token, vehicles)


@contextmanager
def _database_of_kind(kind: str, folder: Path) -> Iterator[str]:
    """A migrated database of ``kind``: a copy of the migrated template of each kind."""
    if kind == "sqlite":
        path = folder / "store.sqlite3"
        shutil.copyfile(migrated_template(), path)
        yield f"sqlite:///{path}"
        return
    with scratch_postgres() as url:
        yield url


@pytest.fixture(params=["sqlite", "postgresql"])
def database_url(request: pytest.FixtureRequest, tmp_path: Path) -> Iterator[str]:
    """The same storage test on the embedded default and on PostgreSQL, each database
    already migrated (a test's own `migrate` finds nothing to do)."""
    with _database_of_kind(request.param, tmp_path) as url:
        yield url


@pytest.fixture(scope="module", params=["sqlite", "postgresql"])
def module_database_url(
    request: pytest.FixtureRequest, tmp_path_factory: pytest.TempPathFactory
) -> Iterator[str]:
    """`database_url` once per module and kind, for a module whose tests only read what
    its fixture stored (tests/README.md, "Read-only fixtures at module scope")."""
    with _database_of_kind(request.param, tmp_path_factory.mktemp("store")) as url:
        yield url


@pytest.fixture
def engine(database_url: str) -> Iterator[Engine]:
    created = make_engine(database_url)
    yield created
    created.dispose()
