"""Logging in, roles, the audit log and logging out, in headless Chromium against the real fleet.

The fleet is shared by the whole session, so every test makes its own users (unique
names) through the admin REST API, and no test fails a login more than once: the hub
limits failed logins per address, and every test here comes from 127.0.0.1.
"""

from __future__ import annotations

import re
import uuid
from collections.abc import Callable, Iterator

import httpx
import pytest
from playwright.sync_api import Page, Route, expect

from gcs.launcher import LocalFleet

pytestmark = [pytest.mark.browser, pytest.mark.integration]

VEHICLE = "sim_1"
FLEET_TIMEOUT_MS = 30_000
PASSWORD_LENGTH = 16

NewUser = Callable[[str], tuple[str, str]]


def _unique(prefix: str) -> str:
    return f"{prefix}_{uuid.uuid4().hex[:10]}"


def _log_in(page: Page, base_url: str, username: str, password: str) -> None:
    """Through the dashboard's login form, as a person would."""
    page.goto(base_url + "/")
    form = page.locator("#login")
    expect(form).to_be_visible(timeout=10_000)
    form.locator('input[name="username"]').fill(username)
    form.locator('input[name="password"]').fill(password)
    form.locator('button[type="submit"]').click()


def _rest_login(base_url: str, username: str, password: str) -> httpx.Client:
    """A REST client holding the session cookie of `username`."""
    client = httpx.Client(base_url=base_url, timeout=30)
    response = client.post("/api/v1/auth/login", json={"username": username, "password": password})
    assert response.status_code == 200, response.text
    return client


@pytest.fixture(scope="module")
def admin_api(fleet: LocalFleet) -> Iterator[httpx.Client]:
    client = _rest_login(fleet.plan.hub_http, "admin", fleet.plan.admin_password)
    try:
        yield client
    finally:
        client.close()


@pytest.fixture
def new_user(admin_api: httpx.Client) -> NewUser:
    """Creates a user with a unique name and the given role; returns (username, password)."""

    def create(role: str) -> tuple[str, str]:
        username = _unique(role)
        password = uuid.uuid4().hex[:PASSWORD_LENGTH]
        response = admin_api.post(
            "/api/v1/users", json={"username": username, "password": password, "role": role}
        )
        assert response.status_code == 201, response.text
        return username, password

    return create


def test_login_screen_comes_first_and_refuses_a_wrong_password(
    page: Page, fleet: LocalFleet
) -> None:
    page.goto(fleet.plan.hub_http + "/")
    form = page.locator("#login")
    expect(form).to_be_visible(timeout=10_000)
    # Nothing of the dashboard shows (or connects) before logging in.
    expect(page.locator("#connection-status")).to_be_hidden()
    expect(page.locator(".vehicle-marker")).to_have_count(0)

    form.locator('input[name="username"]').fill("admin")
    form.locator('input[name="password"]').fill("not-the-password")
    form.locator('button[type="submit"]').click()
    error = page.locator('[data-field="login-error"]')
    expect(error).to_have_text("wrong username or password", timeout=10_000)
    expect(form).to_be_visible()
    expect(form.locator('input[name="password"]')).to_have_value("")

    form.locator('input[name="password"]').fill(fleet.plan.admin_password)
    form.locator('button[type="submit"]').click()
    expect(form).to_be_hidden(timeout=10_000)
    expect(page.locator(".vehicle-marker")).to_have_count(3, timeout=FLEET_TIMEOUT_MS)
    expect(page.locator("#current-user")).to_have_text("admin · admin")
    expect(page.locator("#connection-status")).to_have_attribute("data-state", "connected")
    # Nothing about the session is readable by scripts or kept in storage.
    assert "gcs_session" not in page.evaluate("document.cookie")
    assert page.evaluate("localStorage.length + sessionStorage.length") == 0

    # A reload keeps the session (the HttpOnly cookie), so no second login.
    page.reload()
    expect(page.locator(".vehicle-marker")).to_have_count(3, timeout=FLEET_TIMEOUT_MS)
    expect(page.locator("#login")).to_be_hidden()


def test_a_viewer_sees_the_fleet_but_no_controls(
    page: Page, fleet: LocalFleet, new_user: NewUser
) -> None:
    username, password = new_user("viewer")
    _log_in(page, fleet.plan.hub_http, username, password)

    expect(page.locator("#current-user")).to_have_text(f"{username} · viewer", timeout=10_000)
    rows = page.locator("tr[data-vehicle-id]")
    expect(rows).to_have_count(3, timeout=FLEET_TIMEOUT_MS)
    expect(page.locator(".vehicle-marker")).to_have_count(3)
    expect(rows.first.locator('[data-field="mode"]')).not_to_have_text("", timeout=10_000)
    for action in ("arm", "disarm", "takeoff", "hold", "land", "rtl"):
        expect(page.locator(f'button[data-action="{action}"]')).to_have_count(0)
    expect(page.locator('[data-field="takeoff-altitude"]')).to_have_count(0)
    expect(page.locator('button[data-action="show-audit"]')).to_have_count(0)
    expect(page.locator('button[data-action="logout"]')).to_be_visible()


def test_an_operator_sees_safety_refusals_and_pages_the_audit_log(
    page: Page, fleet: LocalFleet, new_user: NewUser
) -> None:
    base_url = fleet.plan.hub_http
    username, password = new_user("operator")
    # More than one page (50) of audit entries: logins of this operator.
    for _ in range(52):
        _rest_login(base_url, username, password).close()
    _log_in(page, base_url, username, password)
    expect(page.locator("#current-user")).to_have_text(f"{username} · operator", timeout=10_000)
    expect(page.locator('button[data-action="takeoff"]')).to_have_count(3, timeout=FLEET_TIMEOUT_MS)

    # The hub's safety rails refuse a take-off above the site ceiling before it
    # reaches the vehicle; the row says which rule and why.
    row = page.locator(f'tr[data-vehicle-id="{VEHICLE}"]')
    row.locator('input[data-field="takeoff-altitude"]').fill("150")
    row.locator('button[data-action="takeoff"]').click()
    result = row.locator('[data-field="command-result"]')
    expect(result).to_have_attribute("data-tone", "refused", timeout=10_000)
    expect(result).to_contain_text("takeoff: refused — ")
    expect(result).to_contain_text(re.compile(r"150(\.0)? m"))

    page.locator('button[data-action="show-audit"]').click()
    panel = page.locator("#audit-panel")
    expect(panel).to_be_visible()
    entries = panel.locator("tr[data-audit-id]")
    expect(entries).to_have_count(50, timeout=10_000)
    newest = entries.first
    expect(newest.locator('[data-field="action"]')).to_have_text("command")
    expect(newest.locator('[data-field="actor"]')).to_have_text(username)
    expect(newest.locator('[data-field="token"]')).to_have_text("session")
    expect(newest.locator('[data-field="role"]')).to_have_text("operator")
    expect(newest.locator('[data-field="target"]')).to_have_text(VEHICLE)
    expect(newest.locator('[data-field="outcome"]')).to_have_text("refused")
    own_login = entries.nth(1)
    expect(own_login.locator('[data-field="action"]')).to_have_text("login")
    expect(own_login.locator('[data-field="target"]')).to_have_text(username)
    expect(own_login.locator('[data-field="outcome"]')).to_have_text("ok")
    expect(own_login.locator('[data-field="source"]')).to_have_text("127.0.0.1")

    more = panel.locator('button[data-action="audit-more"]')
    expect(more).to_be_visible()
    more.click()
    expect(entries).not_to_have_count(50, timeout=10_000)
    ids = [int(i) for i in entries.evaluate_all("rows => rows.map(r => r.dataset.auditId)")]
    assert len(ids) > 50
    assert ids == sorted(ids, reverse=True), ids
    assert len(set(ids)) == len(ids), ids

    # Refresh goes back to the newest page.
    panel.locator('button[data-action="audit-refresh"]').click()
    expect(entries).to_have_count(50, timeout=10_000)


def test_logout_returns_to_the_login_screen_and_stops_the_feed(
    page: Page, fleet: LocalFleet, new_user: NewUser
) -> None:
    username, password = new_user("operator")
    _log_in(page, fleet.plan.hub_http, username, password)
    status = page.locator("#connection-status")
    expect(status).to_have_attribute("data-state", "connected", timeout=FLEET_TIMEOUT_MS)
    expect(page.locator(".vehicle-marker")).to_have_count(3, timeout=FLEET_TIMEOUT_MS)

    page.locator('button[data-action="logout"]').click()
    expect(page.locator("#login")).to_be_visible(timeout=10_000)
    expect(status).to_be_hidden()
    expect(status).not_to_have_attribute("data-state", "connected")
    expect(page.locator(".vehicle-marker")).to_have_count(0)
    expect(page.locator("tr[data-vehicle-id]")).to_have_count(0)
    expect(page.locator('[data-field="login-error"]')).to_be_hidden()

    # The hub ended the session too: a reload asks for a login again.
    page.reload()
    expect(page.locator("#login")).to_be_visible(timeout=10_000)
    expect(page.locator(".vehicle-marker")).to_have_count(0)


def _disable(admin_api: httpx.Client, username: str) -> None:
    """Disabling an account ends every session it has."""
    response = admin_api.patch(f"/api/v1/users/{username}", json={"disabled": True})
    assert response.status_code == 200, response.text


def test_a_401_on_any_call_brings_back_the_login_screen(
    page: Page, fleet: LocalFleet, new_user: NewUser, admin_api: httpx.Client
) -> None:
    username, password = new_user("operator")
    _log_in(page, fleet.plan.hub_http, username, password)
    row = page.locator(f'tr[data-vehicle-id="{VEHICLE}"]')
    expect(row.locator('button[data-action="takeoff"]')).to_be_visible(timeout=FLEET_TIMEOUT_MS)

    _disable(admin_api, username)
    # Disabling ends the account's sessions, and the hub closes its live feed at once
    # (4401), so the dashboard returns to the login screen without another click.
    expect(page.locator("#login")).to_be_visible(timeout=10_000)
    expect(page.locator('[data-field="login-error"]')).to_contain_text(
        re.compile("session|revoked")
    )
    expect(page.locator("#connection-status")).to_be_hidden()
    expect(page.locator("tr[data-vehicle-id]")).to_have_count(0)
    # And any REST call with the old cookie is refused as well.
    cookies = {c["name"]: c["value"] for c in page.context.cookies()}
    assert httpx.get(f"{fleet.plan.hub_http}/api/v1/vehicles", cookies=cookies).status_code == 401


def test_a_websocket_refused_with_4401_brings_back_the_login_screen(
    page: Page, fleet: LocalFleet, new_user: NewUser, admin_api: httpx.Client
) -> None:
    username, password = new_user("viewer")
    sockets: list[str] = []
    page.on("websocket", lambda socket: sockets.append(socket.url))

    def revoke_after_config(route: Route) -> None:
        # The dashboard loads its config right before opening the WebSocket: end the
        # session in between, so the real hub refuses the socket (close code 4401).
        response = route.fetch()
        _disable(admin_api, username)
        route.fulfill(response=response)

    page.route("**/api/v1/config", revoke_after_config)
    _log_in(page, fleet.plan.hub_http, username, password)
    expect(page.locator("#login")).to_be_visible(timeout=FLEET_TIMEOUT_MS)
    # Whichever the dashboard hears first, the socket's close reason or a REST call's 401,
    # the screen says to log in again.
    expect(page.locator('[data-field="login-error"]')).to_contain_text(
        re.compile("log in again", re.IGNORECASE)
    )
    status = page.locator("#connection-status")
    expect(status).to_be_hidden()
    # It gave up ("stopped") rather than waiting to reconnect ("reconnecting").
    expect(status).to_have_attribute("data-state", "stopped")
    assert len(sockets) == 1, sockets
