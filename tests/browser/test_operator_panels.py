"""The operator's panels in headless Chromium, at a desktop, a tablet and a phone size
(issue 16): the flight-mode picker, the live event feed with a simulator's pre-arm
refusal, and the battery warning on the row and the marker. A screenshot of each run is
saved under test-output/panels/."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import httpx
import pytest
from playwright.sync_api import Browser, Page, expect

from gcs.launcher import LocalFleet
from tests.browser.conftest import SIZES, checked_page, log_in
from tests.conftest import FLEET_SPEEDUP
from tests.support.api import access_token, api_client
from tests.support.processes import running_fleet

pytestmark = [pytest.mark.browser, pytest.mark.integration]

OUTPUT = Path(__file__).resolve().parents[2] / "test-output" / "panels"
WARN_COLOUR = "rgb(245, 185, 66)"  # --warn in frontend/src/styles/base.css


@pytest.fixture(scope="module")
def panels_fleet(tmp_path_factory: pytest.TempPathFactory) -> Iterator[LocalFleet]:
    """A fleet of its own: these tests drain a battery and change modes."""
    with running_fleet(
        tmp_path_factory.mktemp("panels"), vehicles=3, speedup=FLEET_SPEEDUP
    ) as fleet:
        yield fleet


@pytest.fixture(scope="module")
def api(panels_fleet: LocalFleet) -> Iterator[httpx.Client]:
    token = access_token(panels_fleet.plan.hub_http, "admin", panels_fleet.plan.admin_password)
    with api_client(panels_fleet.plan.hub_http, token) as client:
        yield client


@pytest.fixture(params=list(SIZES))
def sized_page(request: pytest.FixtureRequest, browser: Browser) -> Iterator[tuple[Page, str]]:
    with checked_page(browser, *SIZES[request.param]) as page:
        yield page, request.param
        OUTPUT.mkdir(parents=True, exist_ok=True)
        page.screenshot(path=OUTPUT / f"{request.node.originalname}-{request.param}.png")


def _small(size: str) -> bool:
    return size != "desktop"


def _open_drawer(page: Page, size: str, drawer: str) -> None:
    """On a tablet or phone the fleet list and the panels are drawers beside the map."""
    if not _small(size):
        return
    button = page.locator(f'button[data-action="drawer-{drawer}"]')
    if button.get_attribute("aria-expanded") != "true":
        button.click()
    expect(button).to_have_attribute("aria-expanded", "true")


def _select(page: Page, size: str, vehicle: str) -> None:
    _open_drawer(page, size, "fleet")
    page.locator(f'tr[data-vehicle-id="{vehicle}"] td[data-field="mode"]').click()
    _open_drawer(page, size, "ops")
    expect(page.locator('[data-panel="selected-vehicle"]')).to_have_attribute(
        "data-vehicle-id", vehicle
    )


def _assert_touch_targets(page: Page, size: str) -> None:
    if not _small(size):
        return
    for target in page.locator(
        ".ops-panel select:visible, .ops-panel button:visible, .drawer-toggle:visible"
    ).all():
        box = target.bounding_box()
        assert box is not None
        # In Chromium's layout unit (1/64 px): a 44 px box can read 43.99997.
        assert round(min(box["height"], box["width"]) * 64) / 64 >= 44, box


def _command(api: httpx.Client, vehicle: str, **command: object) -> dict[str, object]:
    response = api.post(f"/api/v1/vehicles/{vehicle}/commands", json=command)
    assert response.status_code == 200, response.text
    outcome: dict[str, object] = response.json()["outcome"]
    return outcome


def _log_in(page: Page, fleet: LocalFleet) -> None:
    log_in(page, fleet.plan.hub_http, "admin", fleet.plan.admin_password)
    expect(page.locator("tr[data-vehicle-id]")).to_have_count(3, timeout=30_000)
    # The map stays in view at every size.
    expect(page.locator("#map")).to_be_visible()
    box = page.locator("#map").bounding_box()
    assert box is not None
    assert min(box["width"], box["height"]) >= 300, box


def test_a_mode_picked_from_the_list_is_reported_back(
    sized_page: tuple[Page, str], panels_fleet: LocalFleet, api: httpx.Client
) -> None:
    page, size = sized_page
    vehicle = "sim_1"
    _log_in(page, panels_fleet)
    row = page.locator(f'tr[data-vehicle-id="{vehicle}"]')
    expect(row.locator('[data-field="mode"]')).not_to_have_text("—", timeout=30_000)
    _select(page, size, vehicle)
    picker = page.locator('select[data-field="mode-picker"]')
    expect(picker).to_be_enabled()
    modes = picker.locator("option:not([disabled])").all_inner_texts()
    # ArduCopter's own list (not a generic one), the current mode selected.
    assert {"STABILIZE", "LOITER", "GUIDED", "RTL", "BRAKE"} <= set(modes), modes
    # The row's text as the page holds it (a row in a closed drawer renders no text).
    current = (row.locator('[data-field="mode"]').text_content() or "").strip()
    assert current not in ("", "—")
    # The picker shows the reported mode once the panel has drawn the vehicle's update.
    expect(picker).to_have_value(current)
    wanted = next(mode for mode in ("LOITER", "STABILIZE") if mode != current)

    picker.select_option(wanted)
    expect(page.locator('[data-field="mode-result"]')).to_contain_text("accepted", timeout=30_000)
    # Reported back by the autopilot: the row, the picker and the event feed.
    expect(row.locator('[data-field="mode"]')).to_have_text(wanted, timeout=30_000)
    expect(picker).to_have_value(wanted)
    feed = page.locator('[data-feed="live"]')
    expect(
        feed.locator(f'li[data-kind="mode"][data-vehicle-id="{vehicle}"]').first
    ).to_contain_text(f"mode {wanted}")
    expect(feed.locator('li[data-kind="command"]').first).to_contain_text(
        f"set_mode {wanted}: accepted"
    )
    _assert_touch_targets(page, size)


def test_a_pre_arm_failure_shows_in_the_feed_and_on_the_row(
    sized_page: tuple[Page, str], panels_fleet: LocalFleet, api: httpx.Client
) -> None:
    page, size = sized_page
    vehicle = "sim_2"
    _log_in(page, panels_fleet)
    # ArduCopter refuses to arm in RTL and says why in a STATUSTEXT (AP_Arming's
    # "Arm: ..." on an attempt, "PreArm: ..." on its periodic checks).
    assert _command(api, vehicle, name="set_mode", mode="RTL")["status"] == "accepted"
    assert _command(api, vehicle, name="arm")["status"] != "accepted"

    _open_drawer(page, size, "ops")
    feed = page.locator('[data-feed="live"]')
    failure = feed.locator(f'li[data-category="prearm"][data-vehicle-id="{vehicle}"]').first
    expect(failure).to_contain_text("Arm: RTL mode not armable", timeout=30_000)
    expect(failure).to_have_attribute("data-severity", "2")
    # The feed filters by severity: "error and worse" still shows a critical text.
    feed.locator('[data-field="event-severity-filter"]').select_option("3")
    expect(failure).to_be_visible()

    _open_drawer(page, size, "fleet")
    alert = page.locator(f'tr[data-vehicle-id="{vehicle}"] [data-field="alert"]')
    expect(alert).to_be_visible()
    expect(alert).to_contain_text("Arm: RTL mode not armable")
    alert.locator('button[data-action="acknowledge"]').click()
    expect(alert).to_be_hidden()
    assert _command(api, vehicle, name="set_mode", mode="STABILIZE")["status"] == "accepted"


def test_a_draining_battery_turns_the_marker_and_row_to_the_warning_colour(
    sized_page: tuple[Page, str], panels_fleet: LocalFleet, api: httpx.Client
) -> None:
    page, size = sized_page
    vehicle = "sim_3"
    state = api.get(f"/api/v1/vehicles/{vehicle}").json()["state"]
    percent = float(state["battery_remaining"])
    # The operator's levels (kept in the browser): low just under the pack's charge now.
    low = int(percent) - 3
    page.add_init_script(
        f"localStorage.setItem('gcs.warningLevels', JSON.stringify({{batteryLowPercent: {low}, "
        f"batteryCriticalPercent: {max(0, low - 30)}}}))"
    )
    _log_in(page, panels_fleet)
    _open_drawer(page, size, "fleet")
    row = page.locator(f'tr[data-vehicle-id="{vehicle}"]')
    marker = page.locator(f'#map .vehicle-marker[data-vehicle-id="{vehicle}"]')
    expect(row).to_have_attribute("data-warning", "ok", timeout=30_000)
    expect(marker).to_have_attribute("data-warning", "ok")

    drain = api.put(f"/api/v1/vehicles/{vehicle}/params/SIM_BATT_DRAIN", json={"value": 60})
    assert drain.status_code == 200, drain.text
    try:
        expect(row).to_have_attribute("data-warnbattery", "warning", timeout=60_000)
    finally:
        api.put(f"/api/v1/vehicles/{vehicle}/params/SIM_BATT_DRAIN", json={"value": 0})
    expect(row).to_have_attribute("data-warning", "warning")
    expect(row.locator('td[data-field="battery"]')).to_have_css("color", WARN_COLOUR)
    expect(row.locator("td.vehicle-name")).to_have_css("color", WARN_COLOUR)
    expect(marker).to_have_attribute("data-warning", "warning")
    expect(marker.locator(".vehicle-label")).to_have_css("color", WARN_COLOUR)
    expect(marker.locator('.marker-warning svg[data-icon="warning"]')).to_have_count(1)
    count = page.locator('[data-field="warning-count"]')
    expect(count).to_have_attribute("data-level", "warning")
    expect(count).to_contain_text("1")
