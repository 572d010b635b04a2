"""A finished survey's mosaic is on the dashboard's map after the hub restarts (issue 33):
the dashboard draws every mosaic the hub lists (GET /api/v1/mosaics), not only the one of
the survey it followed in flight. The mosaic is built by the real MosaicService in the
hub's data folder; a hub serves it, stops, and a new hub on the same folder serves it
again to a reloaded page."""

from __future__ import annotations

import asyncio
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pytest
from playwright.sync_api import Browser, expect

from backend.imagery.mosaic.service import MosaicService
from protocol.photos import CameraIntrinsics
from simulator.world.ground import Ground
from tests.browser.conftest import SIZES, checked_page, log_in
from tests.conftest import ADMIN_PASSWORD, hub_settings
from tests.mosaic_photos import HOME, mosaic_of, survey_photos
from tests.support.hub_server import running_hub

pytestmark = [pytest.mark.browser, pytest.mark.integration]

DASHBOARD = Path(__file__).resolve().parents[2] / "frontend" / "dist"
SURVEY = "finished-survey"
CAMERA = CameraIntrinsics(
    sensor_width_mm=13.2,
    sensor_height_mm=8.8,
    image_width_px=640,
    image_height_px=480,
    focal_length_mm=8.8,
)


def _build_mosaic(data_dir: Path) -> None:
    shots = [(-6.0, -6.0, 0.0), (-6.0, 6.0, 0.0), (6.0, 6.0, 180.0), (6.0, -6.0, 180.0)]
    photos = survey_photos(
        data_dir / "photos",
        Ground(*HOME, seed=4),
        CAMERA,
        shots,
        altitude_m=20.0,
        survey_id=SURVEY,
    )

    async def no_area(_: str) -> None:
        return None

    service = MosaicService(data_dir / "mosaics", no_area)
    # In a thread of its own: Playwright's loop already runs in this one.
    with ThreadPoolExecutor(1) as pool:
        pool.submit(lambda: asyncio.run(mosaic_of(service, photos))).result()
    service.close()


def test_a_finished_mosaic_is_on_the_map_after_a_hub_restart(
    browser: Browser, tmp_path: Path
) -> None:
    _build_mosaic(tmp_path)
    for run in ("first", "restarted"):
        # Each run a new hub on the same data folder, and a page of its own.
        with (
            running_hub(hub_settings(tmp_path, frontend_dir=DASHBOARD)) as base_url,
            checked_page(browser, *SIZES["desktop"]) as page,
        ):
            log_in(page, base_url, "admin", ADMIN_PASSWORD)
            layer = page.locator(f'#map .survey-mosaic[data-survey-id="{SURVEY}"]')
            expect(layer).to_be_attached(timeout=30_000)
            page.screenshot(path=f"/tmp/truths-shots/mosaic-{run}.png")
