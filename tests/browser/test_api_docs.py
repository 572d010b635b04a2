"""/docs (Swagger UI) and /redoc render in headless Chromium from the hub alone: no request
leaves the hub, and the hub's Content-Security-Policy refuses nothing."""

from __future__ import annotations

from urllib.parse import urlsplit

import pytest
from playwright.sync_api import Page, Response, Route

pytestmark = pytest.mark.browser


def _offline_and_watched(page: Page, hub: str) -> tuple[list[str], list[str]]:
    """Abort every request that is not to the hub; collect those and any CSP refusals."""
    own = urlsplit(hub).netloc
    elsewhere: list[str] = []
    refused: list[str] = []

    def route(request_route: Route) -> None:
        url = request_route.request.url
        if urlsplit(url).netloc == own or url.startswith(("data:", "blob:")):
            request_route.continue_()
        else:
            elsewhere.append(url)
            request_route.abort()

    page.route("**/*", route)
    page.on(
        "console",
        lambda message: (
            refused.append(message.text) if "Content Security Policy" in message.text else None
        ),
    )
    return elsewhere, refused


def _under_the_hubs_csp(response: Response | None) -> None:
    """The page came with the hub's policy: scripts from the hub only, none inline."""
    assert response is not None
    assert response.ok
    policy = response.headers.get("content-security-policy", "")
    directives = {d.split()[0]: d.split()[1:] for d in policy.split(";") if d.strip()}
    assert directives.get("script-src") == ["'self'"], policy
    assert directives.get("default-src") == ["'self'"], policy


def test_swagger_ui_renders_offline_under_the_csp(page: Page, hub: str) -> None:
    elsewhere, refused = _offline_and_watched(page, hub)
    _under_the_hubs_csp(page.goto(f"{hub}/docs"))
    page.locator(
        ".opblock-summary-path", has_text="/api/v1/vehicles/{vehicle_id}/commands"
    ).first.wait_for(timeout=15_000)
    assert page.locator(".opblock").count() >= 40
    # The sockets, which OpenAPI cannot describe, are named at the top, with their page.
    info = page.locator(".information-container")
    assert "/api/v1/ws" in info.inner_text()
    assert "docs/websockets.md" in info.inner_text()
    assert elsewhere == []
    assert refused == []


def test_redoc_renders_offline_under_the_csp(page: Page, hub: str) -> None:
    elsewhere, refused = _offline_and_watched(page, hub)
    _under_the_hubs_csp(page.goto(f"{hub}/redoc"))
    page.get_by_text("Send a command and return the flight controller's answer.").first.wait_for(
        timeout=15_000
    )
    # The sidebar's logo, which ReDoc asks its vendor's CDN for, comes from the hub.
    logo = page.locator("img[alt='redocly logo']")
    logo.wait_for(timeout=15_000)
    assert urlsplit(logo.evaluate("img => img.currentSrc")).netloc == urlsplit(hub).netloc
    assert logo.evaluate("img => img.complete && img.naturalWidth > 0")
    assert elsewhere == []
    assert refused == []
