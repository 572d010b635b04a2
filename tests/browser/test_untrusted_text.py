"""Text from a vehicle is shown as text, and the page may talk to its own hub only.

A scripted agent (a real WebSocket peer) flies a short flight into the hub's log with a
STATUSTEXT event that is HTML: a link, bold text and an image with a handler, as any
MAVLink peer on the vehicle's link could send. In headless Chromium the replay's event
tooltip shows those characters literally and creates none of the elements. The page's
CSP lets it open its own hub's WebSocket (the live fleet arrives) but no other host's.
"""

from __future__ import annotations

import re
import time
from collections.abc import Callable
from pathlib import Path

import httpx
import pytest
from playwright.sync_api import Page, expect

from backend.settings import REPO_ROOT
from protocol.messages import Event, Telemetry, VehicleState, encode
from tests.browser.conftest import log_in
from tests.conftest import ADMIN_PASSWORD, hub_settings
from tests.support.agents import scripted_agent
from tests.support.hub_server import running_hub
from tests.support.waiting import poll_until

pytestmark = [pytest.mark.browser, pytest.mark.integration]

VEHICLE = "html_1"
HOME = (-35.3632, 149.1652)
HOSTILE = (
    '<a href="https://phish.example/login">Re-enter your password</a>'
    '<b>bold</b><img src="x" onerror="document.title=\'pwned\'">'
)


def _fly_with_hostile_event(base: str, enrol: Callable[[str], str], api: httpx.Client) -> int:
    """A flight of a few seconds, armed to disarmed, with the hostile STATUSTEXT in the
    middle; returns the hub's id for it once closed."""
    start = time.time() - 30
    with scripted_agent(base, VEHICLE, enrol(VEHICLE)) as agent:
        for seq in range(12):
            armed = 1 <= seq <= 10
            state = VehicleState(
                lat=HOME[0] + seq * 1e-5,
                lon=HOME[1] + seq * 1e-5,
                alt_rel=5.0 if armed else 0.0,
                armed=armed,
                mode="GUIDED",
                gps_fix=3,
                heading_deg=45.0,
            )
            agent.send(encode(Telemetry(seq=seq, time=start + seq, state=state)))
        event = Event(seq=0, time=start + 5, kind="statustext", severity=2, text=HOSTILE)
        agent.send(encode(event))

        def closed_flight() -> int | None:
            flights = api.get("/api/v1/flights", params={"vehicle_id": VEHICLE}).json()
            done = [f["id"] for f in flights["flights"] if f["end_time"] is not None]
            events = api.get("/api/v1/events", params={"vehicle_id": VEHICLE}).json()
            stored = any(e["text"] == HOSTILE for e in events["events"])
            return done[0] if done and stored else None

        poll_until(closed_flight, 15, "the flight and its event to be stored")
        flight_id = closed_flight()
    assert flight_id is not None
    return flight_id


def test_an_event_text_with_tags_renders_as_literal_text(page: Page, tmp_path: Path) -> None:
    dashboard = REPO_ROOT / "frontend" / "dist"
    settings = hub_settings(tmp_path, frontend_dir=dashboard)
    if not (dashboard / "index.html").is_file():
        pytest.fail("the dashboard is not built: run scripts/setup.sh (npm run build)")
    with running_hub(settings) as base:
        admin = httpx.post(
            f"{base}/api/v1/auth/token", data={"username": "admin", "password": ADMIN_PASSWORD}
        ).json()["access_token"]
        with httpx.Client(base_url=base, headers={"Authorization": f"Bearer {admin}"}) as api:

            def enrol(vehicle_id: str) -> str:
                issued = api.post(f"/api/v1/vehicles/{vehicle_id}/agent-tokens")
                assert issued.status_code == 201, issued.text
                token: str = issued.json()["token"]
                return token

            flight_id = _fly_with_hostile_event(base, enrol, api)

        log_in(page, base, "admin", ADMIN_PASSWORD)
        # the live fleet arrived over the hub's own WebSocket, which the CSP allows
        expect(page.locator(f'tr[data-vehicle-id="{VEHICLE}"]')).to_be_visible(timeout=15_000)

        page.locator('button[data-action="show-flights"]').click()
        panel = page.locator("#replay-panel")
        row = panel.locator(f'tr[data-flight-id="{flight_id}"]')
        expect(row).to_be_visible(timeout=10_000)
        row.click()
        expect(panel.locator('.replay[data-state="ready"]')).to_be_visible(timeout=15_000)

        marker = page.locator('#map .event-marker[data-kind="statustext"]')
        expect(marker).to_have_count(1)
        marker.hover()
        tooltip = page.locator(".leaflet-tooltip")
        expect(tooltip).to_be_visible()
        expect(tooltip).to_contain_text(HOSTILE)  # the characters, as sent
        assert tooltip.locator("a, b, img").count() == 0, tooltip.inner_html()
        assert page.locator('a[href^="https://phish.example"]').count() == 0
        assert page.title() != "pwned"

        # connect-src is the hub's own origin: a script cannot reach any other host
        blocked = page.evaluate(
            """() => new Promise((resolve) => {
                document.addEventListener('securitypolicyviolation',
                    (e) => resolve(e.effectiveDirective), { once: true });
                try { new WebSocket('ws://127.0.0.1:9/'); } catch (e) { resolve('threw'); }
                setTimeout(() => resolve('allowed'), 3000);
            })"""
        )
        assert blocked in ("connect-src", "threw"), blocked
        csp = page.request.get(base + "/").headers["content-security-policy"]
        assert re.search(r"connect-src 'self';", csp), csp
