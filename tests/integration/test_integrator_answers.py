"""Small answers an integrator reads: the token route says it takes a form, /auth/me says
when the token ends, and the command log gives each command as an object."""

from __future__ import annotations

from collections.abc import Callable

import httpx
import pytest

from tests.conftest import ADMIN_PASSWORD
from tests.support.agents import scripted_agent


def test_json_to_the_token_route_is_told_it_takes_a_form(hub: str) -> None:
    body = {"username": "admin", "password": ADMIN_PASSWORD}
    refused = httpx.post(f"{hub}/api/v1/auth/token", json=body)
    assert refused.status_code == 422
    (problem,) = refused.json()["detail"]
    assert problem["loc"] == ["header", "content-type"]
    assert "takes a form (application/x-www-form-urlencoded)" in problem["msg"]
    assert "got application/json" in problem["msg"]
    assert httpx.post(f"{hub}/api/v1/auth/token", data=body).status_code == 200


def test_me_says_when_an_api_token_expires(admin_api: httpx.Client, hub: str) -> None:
    created = admin_api.post(
        "/api/v1/auth/api-tokens", json={"name": "nightly", "expires_in_days": 7}
    ).json()
    headers = {"Authorization": f"Bearer {created['token']}"}
    me = httpx.get(f"{hub}/api/v1/auth/me", headers=headers).json()
    assert created["expires_at"] is not None
    assert me["expires_at"] == pytest.approx(created["expires_at"])
    forever = admin_api.post(
        "/api/v1/auth/api-tokens", json={"name": "kiosk", "expires_in_days": None}
    ).json()
    headers = {"Authorization": f"Bearer {forever['token']}"}
    assert httpx.get(f"{hub}/api/v1/auth/me", headers=headers).json()["expires_at"] is None


def test_the_command_log_gives_the_command_as_an_object(
    hub: str, admin_api: httpx.Client, enrol: Callable[[str], str]
) -> None:
    with scripted_agent(hub, "c1", enrol("c1")):
        pass  # known and offline: the command is refused and logged
    command = {"name": "takeoff", "altitude": 12.0}
    refused = admin_api.post("/api/v1/vehicles/c1/commands", json=command)
    assert refused.status_code in (409, 422), refused.text  # offline, or no position
    (logged,) = admin_api.get("/api/v1/commands", params={"vehicle_id": "c1"}).json()["commands"]
    assert logged["command"] == command
    assert "command_json" not in logged
    audited = admin_api.get("/api/v1/audit", params={"action": "command"}).json()["entries"][0]
    assert audited["detail"]["command"] == logged["command"]
