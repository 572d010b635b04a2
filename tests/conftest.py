from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import pytest

from backend.settings import HubSettings
from gcs.launcher import FleetPlan, LocalFleet, free_port
from tests.helpers import running_hub

AGENT_TOKEN = "test-agent-token"
# Fast enough that a take-off and landing take seconds, slow enough that the
# 10 Hz telemetry still samples the climb finely.
FLEET_SPEEDUP = 5.0


def hub_settings(data_dir: Path, **overrides: object) -> HubSettings:
    values: dict[str, object] = {
        "port": free_port(),
        "data_dir": data_dir,
        "agent_token": AGENT_TOKEN,
        "frontend_dir": data_dir / "no-dashboard",
    }
    values.update(overrides)
    return HubSettings(**values)  # type: ignore[arg-type]


@pytest.fixture
def hub(tmp_path: Path) -> Iterator[str]:
    """An in-process hub on SQLite in a temporary folder; yields its base URL."""
    with running_hub(hub_settings(tmp_path)) as base_url:
        yield base_url


@pytest.fixture(scope="session")
def fleet(tmp_path_factory: pytest.TempPathFactory) -> Iterator[LocalFleet]:
    """Hub, three simulators and three agents as real processes on loopback."""
    plan = FleetPlan(
        vehicles=3,
        port=free_port(),
        data_dir=tmp_path_factory.mktemp("fleet"),
        speedup=FLEET_SPEEDUP,
        token=AGENT_TOKEN,
    )
    with LocalFleet(plan) as local_fleet:
        local_fleet.start()
        local_fleet.wait_until_ready()
        yield local_fleet
