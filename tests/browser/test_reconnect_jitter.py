"""The dashboard reconnects to its hub as the agents do: full jitter under a doubling cap
(common/retry.py's policy), so the dashboards that lost one hub do not all knock again at
the same instants. With the page's random numbers fixed at 0.2, the waits it announces are
a fifth of the caps (0.5 s, 1 s, 2 s): without the jitter they would be the caps.
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest
from playwright.sync_api import Page, WebSocketRoute, expect

from backend.settings import REPO_ROOT
from tests.browser.conftest import log_in
from tests.conftest import ADMIN_PASSWORD, hub_settings
from tests.support.hub_server import running_hub

pytestmark = [pytest.mark.browser, pytest.mark.integration]

# Every connection state the header shows, in order, kept on <html data-statuses> (the
# page's CSP allows no evaluated strings, so the test reads them as an attribute).
RECORD_STATUS = """
Math.random = () => 0.2;
new MutationObserver(() => {
  const status = document.getElementById("connection-status");
  const seen = document.documentElement.dataset.statuses;
  if (status && status.textContent && !seen?.endsWith("|" + status.textContent)) {
    document.documentElement.dataset.statuses = (seen ?? "") + "|" + status.textContent;
  }
}).observe(document, { subtree: true, childList: true, characterData: true });
"""
DROPS = 3


def test_the_dashboard_reconnects_with_full_jitter(page: Page, tmp_path: Path) -> None:
    dashboard = REPO_ROOT / "frontend" / "dist"
    if not (dashboard / "index.html").is_file():
        pytest.fail("the dashboard is not built: run scripts/setup.sh (npm run build)")
    dropped: list[WebSocketRoute] = []

    def drop_the_first_few(socket: WebSocketRoute) -> None:
        # A hub that goes away right after the upgrade, a few times; then the real one.
        if len(dropped) < DROPS:
            dropped.append(socket)
            socket.close(code=1012, reason="restarting")
        else:
            socket.connect_to_server()

    page.add_init_script(RECORD_STATUS)
    page.route_web_socket("**/api/v1/ws", drop_the_first_few)
    with running_hub(hub_settings(tmp_path, frontend_dir=dashboard)) as base:
        log_in(page, base, "admin", ADMIN_PASSWORD)
        # Three waits announced, then connected to the real hub.
        expect(page.locator("html")).to_have_attribute(
            "data-statuses", re.compile(r"(Reconnecting in .*){3}\|Connected$"), timeout=15_000
        )
        statuses = (page.locator("html").get_attribute("data-statuses") or "").split("|")
    waits = [s for s in statuses if s.startswith("Reconnecting in")]
    assert waits == [
        "Reconnecting in 0.1 s",
        "Reconnecting in 0.2 s",
        "Reconnecting in 0.4 s",
    ], statuses
    assert len(dropped) == DROPS
