"""Flying by hand from the dashboard, in headless Chromium against a real hub, simulator
and agent: take the lease, drag the on-screen stick with the mouse and watch the vehicle
move on the page; hide the page and watch it hold."""

from __future__ import annotations

import re
from collections.abc import Iterator
from pathlib import Path

import pytest
from playwright.sync_api import Dialog, Page, expect

from gcs.launcher import LocalFleet
from tests.browser.conftest import log_in
from tests.support.api import access_token, api_client, send_command
from tests.support.processes import running_fleet
from tests.support.watcher import FleetWatcher, ready

pytestmark = [pytest.mark.browser, pytest.mark.integration, pytest.mark.slow]

VEHICLE = "sim_1"


@pytest.fixture(scope="module")
def hovering(tmp_path_factory: pytest.TempPathFactory) -> Iterator[LocalFleet]:
    """One copter hovering at 10 m, set up as `gcs demo` sets it up (its SYSID_MYGCS the
    agent's id, by the launcher: nothing here makes manual control work)."""
    data_dir: Path = tmp_path_factory.mktemp("pilot")
    with running_fleet(data_dir, vehicles=1, speedup=1.0) as fleet:
        base = fleet.plan.hub_http
        token = access_token(base, "admin", fleet.plan.admin_password)
        with FleetWatcher(base, token) as watcher, api_client(base, token) as api:
            watcher.wait_until(ready(VEHICLE), 60, f"{VEHICLE} ready")
            assert send_command(api, VEHICLE, name="takeoff", altitude=10.0)["status"] == "accepted"
            watcher.wait_until(
                lambda v: (v[VEHICLE]["state"]["alt_rel"] or 0) >= 9.0, 60, f"{VEHICLE} at 10 m"
            )
        yield fleet


def take_control(page: Page, fleet: LocalFleet, source: str = "touch") -> None:
    log_in(page, fleet.plan.hub_http, "admin", fleet.plan.admin_password)
    page.locator(f'tr[data-vehicle-id="{VEHICLE}"]').click()
    pilot = page.locator('[data-panel="pilot"]')
    pilot.locator('select[data-field="pilot-source"]').select_option(source)
    expect(pilot.locator('[data-field="lease-holder"]')).to_contain_text(
        "Nobody flies it by hand", timeout=30_000
    )
    # Nothing is sent before the pilot asks: no stick takes control by itself.
    expect(pilot.locator('[data-field="pilot-status"]')).to_have_text("not flown by hand")
    pilot.locator('button[data-action="take-control"]').click()
    expect(pilot.locator('[data-field="lease-holder"]')).to_have_text(
        "Flown by hand by admin", timeout=30_000
    )
    expect(pilot.locator('[data-field="pilot-status"]')).to_contain_text("flying with")
    expect(pilot.locator('[data-field="pilot-mode"]')).to_have_text("LOITER", timeout=10_000)


def latitude(page: Page) -> float:
    text = page.locator('[data-field="pilot-position"]').text_content() or ""
    return float(text.split(",")[0])


def test_dragging_the_stick_flies_the_vehicle_on_the_page(page: Page, hovering: LocalFleet) -> None:
    take_control(page, hovering)
    start = latitude(page)
    stick = page.locator('[data-stick="right"]')
    stick.scroll_into_view_if_needed()
    box = stick.bounding_box()
    assert box is not None
    x, y = box["x"] + box["width"] / 2, box["y"] + box["height"] / 2
    page.mouse.move(x, y)
    page.mouse.down()
    page.mouse.move(x, y - 60, steps=8)  # pushed forward: pitch forward, to the north
    try:
        expect(page.locator('[data-field="pilot-axes"]')).to_contain_text("x ", timeout=5_000)
        page.wait_for_function(
            f"""() => {{
                const text = document.querySelector('[data-field="pilot-position"]').textContent;
                return (parseFloat(text) - {start}) * 111320 > 5;
            }}""",
            timeout=30_000,
        )
    finally:
        page.mouse.up()
    assert latitude(page) > start  # north, the way the stick pointed (heading 0)
    # The agent's echo of a flown frame: the input-to-vehicle round trip, measured.
    expect(page.locator('[data-field="pilot-delay"]')).to_have_text(re.compile(r"^\d+ ms$"))
    axes = page.locator('[data-field="pilot-axes"]').text_content() or ""
    assert axes.startswith("x ")
    page.locator('[data-panel="pilot"] button[data-action="release-control"]').click()
    expect(page.locator('[data-field="lease-holder"]')).to_contain_text(
        "released by admin", timeout=10_000
    )
    expect(page.locator('[data-field="pilot-mode"]')).to_have_text("BRAKE", timeout=10_000)


def test_hiding_the_page_stops_the_stream_and_the_vehicle_holds(
    page: Page, hovering: LocalFleet
) -> None:
    take_control(page, hovering)
    # What a browser does when the tab goes to the background.
    page.evaluate(
        """() => {
            const hide = (name, value) =>
                Object.defineProperty(document, name, {value, configurable: true});
            hide('visibilityState', 'hidden');
            hide('hidden', true);
            document.dispatchEvent(new Event('visibilitychange'));
        }"""
    )
    pilot = page.locator('[data-panel="pilot"]')
    expect(pilot.locator('[data-field="pilot-status"]')).to_contain_text("stopped: page hidden")
    # The agent's deadman: no input for 0.5 s holds the vehicle and ends the lease.
    expect(pilot.locator('[data-field="pilot-mode"]')).to_have_text("BRAKE", timeout=5_000)
    expect(pilot.locator('[data-field="lease-holder"]')).to_contain_text(
        "manual input stopped for", timeout=5_000
    )


def sent_axes(page: Page) -> dict[str, int]:
    """The last frame the page sent, as the pilot view prints it ("x 463  y 0 ...")."""
    text = page.locator('[data-field="pilot-axes"]').text_content() or ""
    words = text.split()
    return {words[i]: int(words[i + 1]) for i in range(0, len(words) - 1, 2)}


def test_the_keyboard_steps_and_the_shaping_smooths(page: Page, hovering: LocalFleet) -> None:
    take_control(page, hovering, "keyboard")
    # Three presses of W (the second and third as a held key's repeats): three steps of
    # 0.25, capped at the 0.6 sensitivity; then the dead zone and expo shape it.
    for _ in range(3):
        page.keyboard.down("w")
    # The slew limit passes through lower values on the way: wait for where it settles.
    page.wait_for_function(
        "() => /^x 463 /.test(document.querySelector('[data-field=pilot-axes]').textContent)",
        timeout=5_000,
    )
    assert sent_axes(page)["x"] == 463  # (0.6 - 0.05) / 0.95, expo 0.3: 0.463
    page.keyboard.up("w")
    # Let go: back to centre through the slew limit (4 per second), never a jump.
    page.wait_for_function(
        "() => /^x 0 /.test(document.querySelector('[data-field=pilot-axes]').textContent)",
        timeout=5_000,
    )
    page.locator('[data-panel="pilot"] button[data-action="release-control"]').click()
    expect(page.locator('[data-field="lease-holder"]')).to_contain_text("released", timeout=10_000)


def test_a_frozen_gamepad_stops_the_stream_and_the_vehicle_holds(
    page: Page, hovering: LocalFleet
) -> None:
    # A gamepad the page reads through the Gamepad API, whose values the test sets.
    page.add_init_script(
        """(() => {
            const buttons = Array.from({length: 16}, () => ({pressed: false, value: 0}));
            window.fakePad = {id: 'test pad', index: 0, connected: true, mapping: 'standard',
                              timestamp: 1, axes: [0, 0, 0, 0], buttons};
            navigator.getGamepads = () => [window.fakePad];
        })();"""
    )
    take_control(page, hovering, "gamepad")
    # Right stick pushed forward (the standard mapping's axis 3, up is negative)...
    page.evaluate("() => { fakePad.axes = [0, 0, 0, -0.8]; fakePad.timestamp = 2; }")
    page.wait_for_function(
        "() => /^x [1-9]\\d+ /.test(document.querySelector('[data-field=pilot-axes]').textContent)",
        timeout=5_000,
    )
    # ...and then the pad freezes there: the page keeps reading the same values.
    pilot = page.locator('[data-panel="pilot"]')
    expect(pilot.locator('[data-field="pilot-status"]')).to_contain_text(
        "stopped: gamepad frozen", timeout=5_000
    )
    expect(pilot.locator('[data-field="pilot-mode"]')).to_have_text("BRAKE", timeout=5_000)
    expect(pilot.locator('[data-field="lease-holder"]')).to_contain_text(
        "manual input stopped for", timeout=5_000
    )


def test_a_refusal_says_why_and_an_admin_fixes_it_from_the_panel(
    page: Page, hovering: LocalFleet
) -> None:
    """A vehicle whose autopilot would ignore the agent's sticks (SYSID_MYGCS left at
    ArduPilot's 255): the pilot view and the event feed say why within a second; an
    admin sets the parameter the refusal names from the panel, confirms, and flies."""
    base = hovering.plan.hub_http
    token = access_token(base, "admin", hovering.plan.admin_password)
    with api_client(base, token) as api:
        unset = api.put(f"/api/v1/vehicles/{VEHICLE}/params/SYSID_MYGCS", json={"value": 255})
        assert unset.status_code == 200, unset.text
        try:
            log_in(page, base, "admin", hovering.plan.admin_password)
            page.locator(f'tr[data-vehicle-id="{VEHICLE}"]').click()
            pilot = page.locator('[data-panel="pilot"]')
            status = pilot.locator('[data-field="pilot-status"]')
            expect(pilot.locator('[data-field="lease-holder"]')).to_contain_text(
                "Nobody flies it by hand", timeout=30_000
            )
            pilot.locator('button[data-action="take-control"]').click()
            expect(status).to_contain_text(
                "control refused: ArduPilot takes MANUAL_CONTROL only from its GCS "
                "(SYSID_MYGCS = 255); set SYSID_MYGCS to 254",
                timeout=1_000,
            )
            expect(status).to_have_attribute("data-state", "refused")
            live = page.locator('[data-feed="live"] .event-text')
            expect(live.filter(has_text="admin may not take manual control")).to_contain_text(
                "set SYSID_MYGCS to 254", timeout=1_000
            )

            fix = pilot.locator('button[data-action="apply-fix"]')
            expect(fix).to_have_text("Set SYSID_MYGCS to 254")
            # Dismissed: nothing is written, nothing is asked for.
            page.once("dialog", lambda dialog: dialog.dismiss())
            fix.click()
            expect(status).to_contain_text("control refused")
            questions: list[str] = []

            def accept(dialog: Dialog) -> None:
                questions.append(dialog.message)
                dialog.accept()

            page.once("dialog", accept)
            fix.click()
            expect(pilot.locator('[data-field="lease-holder"]')).to_have_text(
                "Flown by hand by admin", timeout=30_000
            )
            expect(status).to_contain_text("flying with")
            expect(fix).to_be_hidden()
            assert "Set SYSID_MYGCS to 254 on sim_1?" in questions[0], questions
            pilot.locator('button[data-action="release-control"]').click()
            expect(pilot.locator('[data-field="lease-holder"]')).to_contain_text(
                "released by admin", timeout=10_000
            )
            # The write went through the hub's audited parameter route, once, as admin.
            entries = api.get("/api/v1/audit", params={"action": "command"}).json()["entries"]
            [write] = [
                entry
                for entry in entries
                if entry["detail"]["command"].get("param") == "SYSID_MYGCS"
                and entry["detail"]["command"].get("value") == 254
            ]
            assert (write["actor"], write["outcome"]) == ("admin", "ok"), write
            assert "GCS's system id" in write["detail"]["safety_critical"]
        finally:
            api.put(f"/api/v1/vehicles/{VEHICLE}/params/SYSID_MYGCS", json={"value": 254})
