"""The live orthomosaic on the dashboard's map, in headless Chromium, against a real fleet
(hub, two simulators rendering their cameras' view, two agents uploading the photos) at ten
times real speed: the mosaic's tiles appear on the map while the drones are still flying.
The screenshot goes to test-output/mosaic/."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import httpx
import pytest
from playwright.sync_api import Page, Response, expect

from common.geodesy import LocalFrame
from gcs.launcher import FleetPlan, LocalFleet, free_port
from tests.browser.conftest import log_in
from tests.support.api import access_token, api_client
from tests.support.hubs import TEST_HUB_ENV
from tests.support.survey_shapes import geojson_area
from tests.support.waiting import poll_until

pytestmark = [pytest.mark.browser, pytest.mark.integration, pytest.mark.slow]

ROOT = Path(__file__).resolve().parents[2]
OUTPUT = ROOT / "test-output" / "mosaic"
VEHICLES = ["sim_1", "sim_2"]
SPEEDUP = 10.0
CAMERA = {
    "sensor_width_mm": 6.4,
    "sensor_height_mm": 4.8,
    "image_width_px": 640,
    "image_height_px": 480,
    "focal_length_mm": 4.8,
}
CAMERA_MODEL = "6.4,4.8,640,480,4.8"  # the agents' --camera-model: the same camera
# A small area just south of the homes, flown slowly (3 m/s: the lanes last long enough in
# real time for the map to show the mosaic while the drones are on them).
WEST_M, SOUTH_M, WIDE_M, DEEP_M = -30.0, -70.0, 70.0, 60.0
FLIGHT_S = 150


@pytest.fixture(scope="module")
def fleet(tmp_path_factory: pytest.TempPathFactory) -> Iterator[LocalFleet]:
    plan = FleetPlan(
        port=free_port(),
        data_dir=tmp_path_factory.mktemp("mosaic-ui"),
        vehicles=len(VEHICLES),
        speedup=SPEEDUP,
        camera_model=CAMERA_MODEL,
    )
    with LocalFleet(plan) as local:
        local.start(
            hub_env={
                **TEST_HUB_ENV,
                "GCS_BASEMAP_URL": "",  # no base map tiles: only the mosaic's are images
                "GCS_SURVEY_UPDATE_INTERVAL_S": "0.2",
                "GCS_COMMANDS_PER_SECOND": "1000",
            }
        )
        local.wait_until_ready(timeout_s=60)
        yield local


def _ready_on_ground(api: httpx.Client) -> bool:
    states = {v["id"]: v["state"] or {} for v in api.get("/api/v1/vehicles").json()}
    return all(
        states.get(vid, {}).get("home_lat") is not None and not states[vid].get("armed")
        for vid in VEHICLES
    )


def _request(plan: FleetPlan) -> dict[str, object]:
    lat, lon, _ = plan.vehicle_home(0)
    frame = LocalFrame(lat, lon)
    corners = [
        (WEST_M, SOUTH_M),
        (WEST_M + WIDE_M, SOUTH_M),
        (WEST_M + WIDE_M, SOUTH_M + DEEP_M),
        (WEST_M, SOUTH_M + DEEP_M),
    ]
    return {
        "area": geojson_area(frame, corners),
        "camera": CAMERA,
        "altitude_m": 30,
        "side_overlap_pct": 60,
        "front_overlap_pct": 70,
        "angle_deg": 0,
        "speed_ms": 3,
        "vehicle_ids": VEHICLES,
    }


def _airborne(api: httpx.Client) -> list[str]:
    states = {v["id"]: v["state"] or {} for v in api.get("/api/v1/vehicles").json()}
    return [
        vid
        for vid in VEHICLES
        if states[vid].get("armed") and (states[vid].get("alt_rel") or 0.0) > 5.0
    ]


def test_mosaic_tiles_appear_on_the_map_while_the_drones_fly(page: Page, fleet: LocalFleet) -> None:
    plan = fleet.plan
    tiles: list[str] = []

    def on_response(response: Response) -> None:
        tile = "/api/v1/mosaics/" in response.url and "/tiles/" in response.url
        if tile and response.status in (200, 304):
            tiles.append(response.url)

    page.on("response", on_response)
    token = access_token(plan.hub_http, "admin", plan.admin_password)
    with api_client(plan.hub_http, token) as api:
        poll_until(lambda: _ready_on_ground(api), 90, "both drones ready with a home")
        log_in(page, plan.hub_http, "admin", plan.admin_password)
        expect(page.locator(".vehicle-marker")).to_have_count(len(VEHICLES), timeout=30_000)

        created = api.post("/api/v1/surveys", json=_request(plan))
        assert created.status_code == 201, created.text
        survey_id = created.json()["survey"]["id"]
        started = api.post(f"/api/v1/surveys/{survey_id}/start")
        assert started.status_code == 200, started.text

        # The dashboard follows the survey that is flying and lays its mosaic on the map.
        loaded = page.locator(".survey-mosaic img.leaflet-tile-loaded")
        expect(loaded.first).to_be_attached(timeout=FLIGHT_S * 1000)
        # Shown, not only fetched: Leaflet fades a loaded tile in.
        expect(loaded.first).to_have_css("opacity", "1")
        # Seen while the drones are still up there: checked after the tiles loaded.
        airborne = _airborne(api)
        progress = api.get(f"/api/v1/surveys/{survey_id}/progress").json()
        OUTPUT.mkdir(parents=True, exist_ok=True)
        page.screenshot(path=OUTPUT / "mosaic-live.png")
        assert airborne, "the tiles came only after the drones landed"
        assert progress["state"] == "flying", progress
        assert tiles, "no tile image was fetched from the hub"
        assert all(f"/api/v1/mosaics/{survey_id}/tiles/" in url for url in tiles)
        # The tiles are pictures of the ground, not blank: decoded by the browser. Any
        # loaded one: as a new revision arrives Leaflet swaps the layer's tiles, and one it
        # is dropping holds its 1x1 placeholder for a moment (what the first read found).
        page.wait_for_function(
            """() => [...document.querySelectorAll(".survey-mosaic img.leaflet-tile-loaded")]
                .some(image => image.naturalWidth === 256 && image.naturalHeight === 256)""",
            timeout=10_000,
        )

        # More photos, newer tiles: the layer is asked again at each revision, tile by tile.
        first = loaded.evaluate_all("images => images.map(image => image.src)")
        page.wait_for_function(
            """first => [...document.querySelectorAll(".survey-mosaic img.leaflet-tile-loaded")]
                .some(image => !first.includes(image.src))""",
            arg=first,
            timeout=60_000,
        )
