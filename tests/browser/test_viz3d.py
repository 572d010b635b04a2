"""The 3D view embedded in the dashboard, in headless Chromium, against the real fleet."""

from __future__ import annotations

import base64
import os
from pathlib import Path

import pytest
from playwright.sync_api import Frame, Page, expect

from backend.viz3d.colours import rgb, vehicle_colour
from gcs.launcher import LocalFleet
from tests.browser.conftest import log_in
from tests.support.waiting import poll_until

pytestmark = [pytest.mark.browser, pytest.mark.integration]

VEHICLE = "sim_1"
# Screenshots land here (CI keeps the folder as the test's output).
OUTPUT = Path(os.environ.get("GCS_TEST_OUTPUT", "test-output")) / "viz3d"


def _canvas_png(frame: Frame) -> bytes:
    return frame.locator("canvas").first.screenshot()


def _changed(frame: Frame, before: bytes) -> bytes | None:
    shot = _canvas_png(frame)
    return shot if shot != before else None


def _colours(png: bytes, page: Page) -> int:
    """How many distinct colours the screenshot has (a blank canvas has one or two)."""
    return int(
        page.evaluate(
            """async (b64) => {
                const img = new Image();
                img.src = "data:image/png;base64," + b64;
                await img.decode();
                const c = new OffscreenCanvas(img.width, img.height);
                const g = c.getContext("2d");
                g.drawImage(img, 0, 0);
                const d = g.getImageData(0, 0, img.width, img.height).data;
                const seen = new Set();
                for (let i = 0; i < d.length; i += 4)
                    seen.add((d[i] << 16) | (d[i + 1] << 8) | d[i + 2]);
                return seen.size;
            }""",
            base64.b64encode(png).decode(),
        )
    )


def test_the_3d_view_shows_the_fleet_and_follows_it(
    page: Page, fleet: LocalFleet, settled_fleet: LocalFleet
) -> None:
    # settled_fleet: landed before it flies, and landed again after, pass or fail.
    OUTPUT.mkdir(parents=True, exist_ok=True)
    sockets: list[str] = []
    page.on("websocket", lambda ws: sockets.append(ws.url))
    log_in(page, fleet.plan.hub_http, "admin", fleet.plan.admin_password)
    expect(page.locator("tr[data-vehicle-id]")).to_have_count(3, timeout=30_000)
    row = page.locator(f'tr[data-vehicle-id="{VEHICLE}"]')
    expect(row.locator('[data-field="armed"]')).to_have_text("disarmed · ready", timeout=30_000)
    # Each vehicle wears the same colour on the 2D map as in the 3D view.
    for vehicle_id in (fleet.vehicle_id(index) for index in range(3)):
        label = page.locator(f'.vehicle-marker[data-vehicle-id="{vehicle_id}"] .vehicle-label')
        shown = label.evaluate("e => getComputedStyle(e).borderLeftColor")
        assert shown == "rgb({}, {}, {})".format(*rgb(vehicle_colour(vehicle_id))), vehicle_id

    page.locator(".viz3d-toggle").click()
    iframe = page.frame_locator(".viz3d-pane iframe")
    # viser's client connected through the hub's relay, under /viz.
    expect(iframe.locator("canvas").first).to_be_visible(timeout=30_000)
    viz = page.frame(url=lambda url: "/viz/" in url)
    assert viz is not None
    # The scene arrived: the vehicles' nodes are in viser's scene tree.
    expect(iframe.get_by_text(VEHICLE, exact=False).first).to_be_attached(timeout=30_000)
    assert any(url.endswith("/viz") for url in sockets), sockets
    # This viewer's own replay panel (tests/unit/viz3d/test_viz_replay.py drives it).
    expect(iframe.get_by_text("Replay a flight").first).to_be_attached(timeout=30_000)

    before = _canvas_png(viz)
    (OUTPUT / "fleet-on-the-ground.png").write_bytes(before)
    assert _colours(before, page) > 20, "the 3D canvas is blank"

    # Selecting a vehicle on the dashboard turns this page's own 3D viewer to it (the
    # camera itself: tests/unit/viz3d/test_viz_viewers.py).
    with page.expect_response(
        lambda r: "/viz/viewers/" in r.url and r.request.method == "POST", timeout=30_000
    ) as turned:
        row.locator('[data-field="id"], td').first.click()
    assert turned.value.status == 200, turned.value.text()
    assert turned.value.json()["vehicle_id"] == VEHICLE

    row.locator('input[data-field="takeoff-altitude"]').fill("15")
    row.locator('button[data-action="takeoff"]').click()
    expect(row.locator('[data-field="command-result"]')).to_contain_text("accepted", timeout=30_000)
    page.wait_for_function(
        """(id) => {
            const row = document.querySelector(`tr[data-vehicle-id="${id}"]`);
            const cell = row && row.querySelector('[data-field="alt_rel"]');
            return parseFloat(cell ? cell.textContent : "") >= 8;
        }""",
        arg=VEHICLE,
        timeout=60_000,
    )
    # The canvas redraws as scene batches arrive: wait for one drawn after the climb.
    after = poll_until(lambda: _changed(viz, before), 30, "the canvas to change")
    (OUTPUT / "vehicle-climbed.png").write_bytes(after)
    assert _colours(after, page) > 20

    # The suite's shared fleet: the next test that flies it expects its vehicles landed.
    row.locator('button[data-action="land"]').click()
    expect(row.locator('[data-field="armed"]')).to_contain_text("disarmed", timeout=120_000)
