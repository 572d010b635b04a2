"""One fleet for the mission tests of this package, with a farmland base map, and the
pages they draw on: a desktop one beside the panel, and one at each screen size."""

from __future__ import annotations

from collections.abc import Iterator

import httpx
import pytest
from playwright.sync_api import Browser, Page

from gcs.launcher import DEFAULT_HOME, FleetPlan, LocalFleet, free_port
from tests.browser.conftest import SIZES, checked_page
from tests.conftest import FLEET_SPEEDUP
from tests.support.api import access_token, api_client
from tests.support.hubs import TEST_HUB_ENV
from tests.support.map_tiles import farmland_tiles, write_mbtiles
from tests.support.mission_editor import vehicle_states
from tests.support.waiting import poll_until


@pytest.fixture(scope="package")
def mission_fleet(tmp_path_factory: pytest.TempPathFactory) -> Iterator[LocalFleet]:
    """A fleet of its own, with nothing online and a farmland tile set as its base map:
    the README's picture is made here."""
    data_dir = tmp_path_factory.mktemp("mission-fleet")
    (data_dir / "tiles").mkdir(mode=0o700)
    tiles = farmland_tiles(DEFAULT_HOME[:2], range(14, 20), radius_m=450)
    write_mbtiles(data_dir / "tiles" / "farmland.mbtiles", tiles, attribution="Made-up farmland")
    plan = FleetPlan(port=free_port(), data_dir=data_dir, vehicles=3, speedup=FLEET_SPEEDUP)
    with LocalFleet(plan) as fleet:
        fleet.start(hub_env={**TEST_HUB_ENV, "GCS_BASEMAP_URL": ""})
        fleet.wait_until_ready()
        yield fleet


@pytest.fixture(scope="package")
def api(mission_fleet: LocalFleet) -> Iterator[httpx.Client]:
    plan = mission_fleet.plan
    with api_client(plan.hub_http, access_token(plan.hub_http, "admin", plan.admin_password)) as c:
        poll_until(
            lambda: sum(bool(s.get("lat")) for s in vehicle_states(c).values()) == plan.vehicles,
            60,
            "every vehicle with a position",
        )
        yield c


def _context_page(browser: Browser, size: str) -> Iterator[Page]:
    # The tablet and the phone have touch screens (a long press opens "fly here") and a
    # mouse as well, which draws the mission as it would on a desktop.
    with checked_page(
        browser, *SIZES[size], accept_downloads=True, has_touch=size != "desktop"
    ) as opened:
        yield opened


@pytest.fixture
def wide_page(browser: Browser) -> Iterator[Page]:
    """1920 by 1080: room for the mission panel beside the drawing."""
    yield from _context_page(browser, "desktop")


@pytest.fixture(params=list(SIZES))
def sized_page(browser: Browser, request: pytest.FixtureRequest) -> Iterator[tuple[Page, str]]:
    yield from ((page, request.param) for page in _context_page(browser, request.param))
