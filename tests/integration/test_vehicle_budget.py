"""Every route that reaches a vehicle spends from one per-user budget, the commands'
budget: parameters and missions too, with the same 429 and Retry-After."""

from __future__ import annotations

from pathlib import Path

import httpx
import pytest

import backend.hub.start
from backend.auth.rate_limit import Limit, RateLimiter
from tests.conftest import ADMIN_PASSWORD, hub_settings
from tests.support.agents import scripted_agent
from tests.support.api import access_token, api_client
from tests.support.hub_server import running_hub

VEHICLE = "b1"
Route = tuple[str, str, dict[str, object] | None]
ROUTES: list[Route] = [
    ("POST", f"/api/v1/vehicles/{VEHICLE}/commands", {"name": "land"}),
    ("GET", f"/api/v1/vehicles/{VEHICLE}/params", None),
    ("GET", f"/api/v1/vehicles/{VEHICLE}/params/RTL_ALT", None),
    ("PUT", f"/api/v1/vehicles/{VEHICLE}/params/RTL_ALT", {"value": 3000}),
    ("POST", f"/api/v1/vehicles/{VEHICLE}/mission", {"items": [{"command": 20}]}),
    ("GET", f"/api/v1/vehicles/{VEHICLE}/mission", None),
    ("PUT", f"/api/v1/vehicles/{VEHICLE}/mission/current", {"seq": 1}),
    ("DELETE", f"/api/v1/vehicles/{VEHICLE}/mission", None),
]


@pytest.fixture
def frozen_limits(monkeypatch: pytest.MonkeyPatch) -> None:
    """The hub's limiters on a clock that stands still: a spent budget stays spent for
    the whole test, however slowly the machine runs it."""

    def frozen(limit: Limit) -> RateLimiter:
        return RateLimiter(limit, clock=lambda: 1000.0)

    monkeypatch.setattr(backend.hub.start, "RateLimiter", frozen)


def _call(api: httpx.Client, route: Route) -> httpx.Response:
    method, path, body = route
    return api.request(method, path, json=body)


@pytest.mark.usefixtures("frozen_limits")
def test_every_vehicle_route_shares_the_commands_budget(tmp_path: Path) -> None:
    with running_hub(hub_settings(tmp_path, commands_per_second=len(ROUTES))) as hub:
        token = access_token(hub, "admin", ADMIN_PASSWORD)
        with api_client(hub, token) as admin:
            enrolled = admin.post(f"/api/v1/vehicles/{VEHICLE}/agent-tokens").json()
            with scripted_agent(hub, VEHICLE, enrolled["token"]):
                pass  # known and offline: each route answers at once, without the budget
            within = [_call(admin, route) for route in ROUTES]
            beyond = [_call(admin, route) for route in ROUTES]
    for route, answer in zip(ROUTES, within, strict=True):
        assert answer.status_code != 429, (route, answer.text)
    for route, answer in zip(ROUTES, beyond, strict=True):
        assert answer.status_code == 429, (route, answer.text)
        assert answer.headers["Retry-After"] == "1", route
        assert "too many commands" in answer.json()["detail"], route


@pytest.mark.usefixtures("frozen_limits")
def test_a_group_command_spends_the_budget_of_parameters_and_missions(tmp_path: Path) -> None:
    with running_hub(hub_settings(tmp_path, commands_per_second=2)) as hub:
        token = access_token(hub, "admin", ADMIN_PASSWORD)
        with api_client(hub, token) as admin:
            for vehicle in ("g1", "g2"):
                enrolled = admin.post(f"/api/v1/vehicles/{vehicle}/agent-tokens").json()
                with scripted_agent(hub, vehicle, enrolled["token"]):
                    pass
            group = {"vehicle_ids": ["g1", "g2"], "command": {"name": "land"}}
            sent = admin.post("/api/v1/fleet/commands", json=group)
            read = admin.get("/api/v1/vehicles/g1/params")
    assert sent.status_code == 200, sent.text
    assert read.status_code == 429, read.text


def test_the_openapi_document_names_the_429_of_every_vehicle_route(hub: str) -> None:
    paths = httpx.get(f"{hub}/openapi.json").json()["paths"]
    for method, path, _ in ROUTES:
        operation = paths[path.replace(VEHICLE, "{vehicle_id}").replace("RTL_ALT", "{param}")]
        responses = operation[method.lower()]["responses"]
        assert "Retry-After" in responses["429"]["headers"], (method, path)
