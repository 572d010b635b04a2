"""The map's base layers and vehicles in headless Chromium, at three screen sizes.

A hub with no online base map and one offline MBTiles file made here: the file is the
base map (its tiles come from /tiles/... with a 200 and the PNG written; a screenshot at
each size goes to test-output/base-maps/), and vehicles whose labels would overlap show
one label with a count instead.
"""

from __future__ import annotations

import math
import re
from collections.abc import Iterator
from pathlib import Path

import pytest
from playwright.sync_api import Browser, Page, expect

from gcs.launcher import DEFAULT_HOME, FleetPlan, LocalFleet, free_port
from tests.browser.conftest import SIZES, checked_page, log_in
from tests.support.hubs import TEST_HUB_ENV
from tests.support.map_tiles import png_tile, write_mbtiles

pytestmark = [pytest.mark.browser, pytest.mark.integration]

TILE_ZOOMS = range(12, 18)
TILE_RADIUS = 8  # tiles each way around home, per zoom
# Two colours in a checkerboard, so each tile is told apart from its neighbours.
EVEN, ODD = png_tile((214, 140, 60)), png_tile((120, 170, 90))
FLEET_TIMEOUT_MS = 60_000
OUTPUT = Path(__file__).resolve().parents[2] / "test-output" / "base-maps"


def _tile_of(lat: float, lon: float, zoom: int) -> tuple[int, int]:
    n = 2**zoom
    x = int((lon + 180) / 360 * n)
    y = int((1 - math.asinh(math.tan(math.radians(lat))) / math.pi) / 2 * n)
    return x, y


def _field_tiles() -> dict[tuple[int, int, int], bytes]:
    tiles = {}
    for zoom in TILE_ZOOMS:
        cx, cy = _tile_of(DEFAULT_HOME[0], DEFAULT_HOME[1], zoom)
        for x in range(cx - TILE_RADIUS, cx + TILE_RADIUS + 1):
            for y in range(cy - TILE_RADIUS, cy + TILE_RADIUS + 1):
                tiles[(zoom, x, y)] = EVEN if (x + y) % 2 == 0 else ODD
    return tiles


@pytest.fixture(scope="module")
def tiled_fleet(tmp_path_factory: pytest.TempPathFactory) -> Iterator[LocalFleet]:
    data_dir = tmp_path_factory.mktemp("tiled-fleet")
    (data_dir / "tiles").mkdir(mode=0o700)
    write_mbtiles(data_dir / "tiles" / "field.mbtiles", _field_tiles(), attribution="Test field")
    plan = FleetPlan(port=free_port(), data_dir=data_dir, vehicles=3, speedup=5.0)
    with LocalFleet(plan) as fleet:
        fleet.start(
            hub_env={**TEST_HUB_ENV, "GCS_BASEMAP_URL": ""}
        )  # nothing online: the offline set
        fleet.wait_until_ready()
        yield fleet


@pytest.fixture
def sized_page(browser: Browser, request: pytest.FixtureRequest) -> Iterator[Page]:
    with checked_page(browser, *SIZES[request.param]) as page:
        yield page


@pytest.mark.parametrize("sized_page", list(SIZES), indirect=True)
def test_an_offline_mbtiles_file_is_the_base_map(sized_page: Page, tiled_fleet: LocalFleet) -> None:
    page = sized_page
    with page.expect_response(
        lambda r: "/tiles/field/" in r.url and r.status == 200, timeout=30_000
    ) as first:
        log_in(page, tiled_fleet.plan.hub_http, "admin", tiled_fleet.plan.admin_password)
    expect(page.locator(".vehicle-marker")).to_have_count(3, timeout=FLEET_TIMEOUT_MS)
    expect(page.locator("#map")).to_have_attribute("data-basemap", "field")
    # A tile the map asked for: served with the PNG this test wrote for that z/x/y.
    response = first.value
    assert response.status == 200
    assert response.headers["content-type"] == "image/png"
    assert "max-age" in response.headers["cache-control"]
    z, x, y = (int(part) for part in response.url.split("?")[0].split("/")[-3:])
    assert response.body() == _field_tiles()[(z, x, y)]

    # The map shows it: at a point of the map away from the vehicles, the tile that
    # covers it is one of the set's, loaded, shown and opaque.
    page.wait_for_timeout(400)  # the fade-in of the tiles (Leaflet's 0.2 s), for the picture
    page.wait_for_function(
        """() => {
            const map = document.getElementById('map').getBoundingClientRect();
            const [px, py] = [map.left + 12, map.bottom - 40];
            return [...document.querySelectorAll('#map img.leaflet-tile-loaded')].some((img) => {
                const r = img.getBoundingClientRect();
                return img.src.includes('/tiles/field/') && img.naturalWidth === 256
                    && r.left <= px && px < r.right && r.top <= py && py < r.bottom
                    && getComputedStyle(img).opacity === '1'
                    && getComputedStyle(img).visibility === 'visible';
            });
        }""",
        timeout=30_000,
    )
    expect(page.locator('[data-field="basemap-notice"]')).to_be_hidden()
    expect(page.locator(".leaflet-control-attribution")).to_contain_text("Test field")

    OUTPUT.mkdir(parents=True, exist_ok=True)
    width, height = page.viewport_size["width"], page.viewport_size["height"]  # type: ignore[index]
    path = OUTPUT / f"offline-base-map-{width}x{height}.png"
    page.screenshot(path=str(path))
    assert path.stat().st_size > 10_000


@pytest.mark.parametrize("sized_page", ["desktop"], indirect=True)
def test_labels_that_would_overlap_merge_into_one_with_a_count(
    sized_page: Page, tiled_fleet: LocalFleet
) -> None:
    page = sized_page
    log_in(page, tiled_fleet.plan.hub_http, "admin", tiled_fleet.plan.admin_password)
    markers = page.locator(".vehicle-marker")
    expect(markers).to_have_count(3, timeout=FLEET_TIMEOUT_MS)
    shown = page.locator(".vehicle-marker:not([hidden])")

    # Zoomed out, the three vehicles (15 m apart) are on one spot: one label, "+2".
    for _ in range(7):
        page.locator(".leaflet-control-zoom-out").click()
        page.wait_for_timeout(300)  # each zoom animates for 0.25 s
    expect(shown).to_have_count(1, timeout=10_000)
    expect(shown.locator(".vehicle-cluster-count")).to_have_text("+2")
    expect(shown).to_have_attribute("data-cluster-size", "3")

    # Clicking the count zooms in until they part: no two shown labels overlap, ever.
    for _ in range(8):
        if shown.count() == 3:
            break
        shown.first.locator(".vehicle-cluster-count").click()
        page.wait_for_timeout(400)
    expect(shown).to_have_count(3, timeout=10_000)
    boxes = [shown.nth(i).locator(".vehicle-label-row").bounding_box() for i in range(3)]
    for i, a in enumerate(boxes):
        for b in boxes[i + 1 :]:
            assert a
            assert b
            apart = (
                a["x"] + a["width"] <= b["x"]
                or b["x"] + b["width"] <= a["x"]
                or a["y"] + a["height"] <= b["y"]
                or b["y"] + b["height"] <= a["y"]
            )
            assert apart, (a, b)
    expect(page.locator(".vehicle-cluster-count:visible")).to_have_count(0)


def test_tile_sets_are_listed_by_name_in_the_switcher(
    page: Page, tiled_fleet: LocalFleet, tmp_path: Path
) -> None:
    log_in(page, tiled_fleet.plan.hub_http, "admin", tiled_fleet.plan.admin_password)
    switcher = page.locator(".leaflet-control-layers")
    expect(switcher).to_be_visible(timeout=20_000)
    switcher.hover()
    names = page.locator(".leaflet-control-layers-base label")
    expect(names).to_have_text(["field", "Grid (no tiles)"])
    overlays = page.locator(".leaflet-control-layers-overlays label")
    expect(overlays).to_have_text(["Trails", "Geofence"])
    trails = overlays.filter(has_text="Trails")
    # Trails are on by default; the check box takes their canvas off the map and back.
    expect(page.locator("#map .trail-layer")).to_have_count(1)
    trails.locator("input").uncheck()
    expect(page.locator("#map .trail-layer")).to_have_count(0)
    trails.locator("input").check()
    expect(page.locator("#map .trail-layer")).to_have_count(1)
    # The grid is a choice here (a tile set exists), so the map has nothing to say.
    names.filter(has_text="Grid").click()
    expect(page.locator("#map")).to_have_attribute("data-basemap", "Grid (no tiles)")
    expect(page.locator("#map")).to_have_class(re.compile(r"\bno-basemap\b"))
    expect(page.locator('[data-field="basemap-notice"]')).to_be_hidden()


def test_with_nothing_reachable_and_nothing_installed_the_map_says_so(
    page: Page, tmp_path: Path
) -> None:
    plan = FleetPlan(port=free_port(), data_dir=tmp_path / "data", vehicles=0)
    with LocalFleet(plan) as hub:
        # A street map nobody answers for (the discard port), and no tiles folder.
        hub.start(hub_env={**TEST_HUB_ENV, "GCS_BASEMAP_URL": "http://127.0.0.1:9/{z}/{x}/{y}.png"})
        hub.wait_until_ready()
        log_in(page, plan.hub_http, "admin", plan.admin_password)
        notice = page.locator('[data-field="basemap-notice"]')
        expect(notice).to_have_text(
            "No base map: street map is unreachable and the hub has no offline tiles "
            "(add .mbtiles or .pmtiles files with `gcs tiles import`).",
            timeout=30_000,
        )
        box = notice.bounding_box()
        assert box is not None
        assert box["height"] < 30  # one line
        expect(page.locator("#map")).to_have_class(re.compile(r"\bno-basemap\b"))
