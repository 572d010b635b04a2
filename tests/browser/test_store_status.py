"""The dashboard's header says when the hub's store is away (a database outage, a full
disk), what it holds meanwhile, and clears once the store is back: the live view and
the commands carry on, so nothing else on the page would show it. Real headless
Chromium, a real hub whose PostgreSQL is behind a proxy the test cuts, and an agent
streaming telemetry (the writer notices an outage when it writes)."""

from __future__ import annotations

import threading
from pathlib import Path

import pytest
from playwright.sync_api import Page, expect

from tests.browser.conftest import log_in
from tests.conftest import ADMIN_PASSWORD, POSTGRES_ADDRESS, hub_settings, scratch_postgres
from tests.support.agents import scripted_agent, telemetry_frame
from tests.support.api import access_token, api_client
from tests.support.hub_server import running_hub
from tests.support.tcp_proxy import CuttableProxy

pytestmark = [pytest.mark.browser, pytest.mark.integration]

DIST = Path(__file__).resolve().parents[2] / "frontend" / "dist"


def test_the_header_reports_a_store_outage_and_its_end(page: Page, tmp_path: Path) -> None:
    host, _, port = POSTGRES_ADDRESS.rpartition(":")
    with CuttableProxy((host, int(port))) as proxy, scratch_postgres() as url:
        proxied = url.replace(POSTGRES_ADDRESS, f"127.0.0.1:{proxy.port}")
        settings = hub_settings(tmp_path, database_url=proxied, frontend_dir=DIST)
        with running_hub(settings) as base:
            with api_client(base, access_token(base, "admin", ADMIN_PASSWORD)) as api:
                agent_token = api.post("/api/v1/vehicles/v1/agent-tokens").json()["token"]
            log_in(page, base, "admin", ADMIN_PASSWORD)
            status = page.locator("#store-status")
            expect(page.locator("#connection-status")).to_have_text("Connected", timeout=15_000)
            expect(status).to_be_hidden()
            with scripted_agent(base, "v1", agent_token) as agent:
                stop = threading.Event()

                def stream() -> None:
                    seq = 0
                    while not stop.wait(0.1):  # the agent's 10 Hz
                        agent.send(telemetry_frame(seq))
                        seq += 1

                streamer = threading.Thread(target=stream, daemon=True)
                streamer.start()
                try:
                    proxy.cut()
                    expect(status).to_be_visible(timeout=20_000)
                    expect(status).to_contain_text("Store unavailable")
                    expect(status).to_have_attribute("data-state", "degraded")
                    proxy.start()
                    expect(status).to_be_hidden(timeout=20_000)
                finally:
                    stop.set()
                    streamer.join(5)
