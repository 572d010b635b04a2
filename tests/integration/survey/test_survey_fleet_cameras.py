"""A fleet's own camera over the real hub, a simulated drone and its agent (which says its
camera in its hello): the hub offers it as a survey preset named after the drone, a survey
planned with it passes, and one planned for another camera is refused before take-off (in
the preview and at create) with the reason, not later when the photos reach the hub."""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

import httpx
import pytest

from gcs.demo_camera import DEMO_CAMERA_MODEL
from gcs.launcher import FleetPlan, LocalFleet, free_port
from tests.support.api import access_token, api_client
from tests.support.hubs import TEST_HUB_ENV
from tests.support.watcher import FleetWatcher, ready

pytestmark = pytest.mark.integration

NORTH = 1 / 111_320
FLEET_PRESET = f"fleet:{DEMO_CAMERA_MODEL}"
MISMATCH = (
    "sim_1's camera is 6.4x4.8 mm, 1280x960 px, 4.8 mm, the plan assumes 13.2x8.8 mm, "
    "5472x3648 px, 8.8 mm (DJI Phantom 4 Pro): its photos would be refused; plan with its "
    f"camera (preset {FLEET_PRESET})"
)


@pytest.fixture(scope="module")
def fleet(tmp_path_factory: pytest.TempPathFactory) -> Iterator[LocalFleet]:
    plan = FleetPlan(
        port=free_port(),
        data_dir=tmp_path_factory.mktemp("fleet-cameras"),
        vehicles=1,
        camera_model=DEMO_CAMERA_MODEL,
    )
    with LocalFleet(plan) as local:
        local.start(hub_env=TEST_HUB_ENV)
        local.wait_until_ready(timeout_s=60)
        yield local


@pytest.fixture(scope="module")
def token(fleet: LocalFleet) -> str:
    return access_token(fleet.plan.hub_http, "admin", fleet.plan.admin_password)


@pytest.fixture(scope="module")
def home(fleet: LocalFleet, token: str) -> tuple[float, float]:
    """Where sim_1 is, once it is ready to plan for (a fix and a home)."""
    with FleetWatcher(fleet.plan.hub_http, token) as watcher:
        watcher.wait_until(ready("sim_1"), 60, "sim_1 ready with a home")
        state = watcher.state("sim_1")
    return state["lat"], state["lon"]


@pytest.fixture
def api(fleet: LocalFleet, token: str) -> Iterator[httpx.Client]:
    with api_client(fleet.plan.hub_http, token) as client:
        yield client


def _request(home: tuple[float, float], camera: str) -> dict[str, Any]:
    """An 80 x 60 m area 30 m north of the drone."""
    lon, lat = home[1], home[0] + 30 * NORTH
    east = NORTH / 0.8  # about a metre east at -35°
    corners = [(0, 0), (80, 0), (80, 60), (0, 60), (0, 0)]
    ring = [[lon + x * east, lat + y * NORTH] for x, y in corners]
    return {
        "area": {"type": "Polygon", "coordinates": [ring]},
        "camera": camera,
        "altitude_m": 30,
        "angle_deg": 0,
        "vehicle_ids": ["sim_1"],
    }


def test_the_drones_camera_is_offered_as_a_preset_named_after_it(
    api: httpx.Client, home: tuple[float, float]
) -> None:
    presets = api.get("/api/v1/surveys/cameras").json()
    first = presets[0]
    assert first["id"] == FLEET_PRESET
    assert first["name"] == "sim_1 camera (6.4x4.8 mm, 1280x960 px, 4.8 mm)"
    assert first["vehicle_ids"] == ["sim_1"]
    assert "dji_phantom4_pro" in [preset["id"] for preset in presets]

    preview = api.post("/api/v1/surveys/preview", json=_request(home, FLEET_PRESET))
    assert preview.status_code == 200, preview.text
    rules = [v["rule"] for v in preview.json()["parts"][0]["check"]["violations"]]
    assert "survey_camera" not in rules
    # GSD = 30 m * 6.4 mm * 100 / (1280 px * 4.8 mm)
    assert preview.json()["gsd_cm"] == pytest.approx(3.125)


def test_another_camera_is_refused_before_take_off_with_the_reason(
    api: httpx.Client, home: tuple[float, float]
) -> None:
    body = _request(home, "dji_phantom4_pro")
    preview = api.post("/api/v1/surveys/preview", json=body)
    assert preview.status_code == 200, preview.text
    assert preview.json()["ok"] is False
    check = preview.json()["parts"][0]["check"]
    assert {"rule": "survey_camera", "message": MISMATCH} in [
        {"rule": v["rule"], "message": v["message"]} for v in check["violations"]
    ]

    created = api.post("/api/v1/surveys", json=body)
    assert created.status_code == 422, created.text
    refusal = created.json()
    camera = [v for v in refusal["violations"] if v["rule"] == "survey_camera"]
    assert camera == [{**camera[0], "message": MISMATCH, "vehicle_id": "sim_1"}]
    assert api.get("/api/v1/surveys").json()["surveys"] == []  # nothing kept
