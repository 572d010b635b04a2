"""The API answers what its OpenAPI document says: a wrong method gets a 405 whose Allow
names every method the path takes (the dashboard's files at "/" used to answer first), and
each route documents its error statuses with their body models."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import httpx
import pytest

from tests.conftest import ADMIN_PASSWORD, hub_settings
from tests.support.api import access_token, api_client
from tests.support.hub_server import running_hub


@pytest.fixture
def hub_with_dashboard(tmp_path: Path) -> Iterator[str]:
    dashboard = tmp_path / "dashboard"
    dashboard.mkdir()
    (dashboard / "index.html").write_text("<!doctype html><title>dashboard</title>")
    with running_hub(hub_settings(tmp_path, frontend_dir=dashboard)) as base:
        yield base


def _allow(response: httpx.Response) -> set[str]:
    return {method.strip() for method in response.headers["allow"].split(",")}


@pytest.mark.parametrize(
    ("method", "path", "allowed"),
    [
        ("OPTIONS", "/api/v1/users", {"GET", "POST"}),
        ("PATCH", "/api/v1/vehicles/v1/safety-rails", {"GET", "PUT", "DELETE"}),
        ("GET", "/api/v1/fleet/commands", {"POST"}),
        ("POST", "/api/v1/agent-tokens/7", {"DELETE"}),
        # a literal path is not also its templated neighbour's (/surveys/{survey_id}: GET)
        ("OPTIONS", "/api/v1/surveys/preview", {"POST"}),
        ("GET", "/api/v1/surveys/import", {"POST"}),  # not a survey id: ids are hex
    ],
)
def test_wrong_method_names_every_allowed_method(
    hub_with_dashboard: str, method: str, path: str, allowed: set[str]
) -> None:
    token = access_token(hub_with_dashboard, "admin", ADMIN_PASSWORD)
    with api_client(hub_with_dashboard, token) as api:
        response = api.request(method, path)
    assert response.status_code == 405, response.text
    assert _allow(response) == allowed


def test_unknown_api_path_is_a_json_404_and_the_dashboard_still_loads(
    hub_with_dashboard: str,
) -> None:
    with httpx.Client(base_url=hub_with_dashboard) as client:
        missing = client.get("/api/v1/no-such-thing")
        assert missing.status_code == 404
        assert missing.headers["content-type"] == "application/json"
        page = client.get("/")
        assert page.status_code == 200
        assert "dashboard" in page.text


def test_every_operation_documents_its_error_statuses(hub: str) -> None:
    document = httpx.get(f"{hub}/openapi.json").json()
    for path, operations in document["paths"].items():
        for method, operation in operations.items():
            responses = operation["responses"]
            label = f"{method.upper()} {path}"
            if operation.get("x-required-permission") != "public":
                assert {"401", "403", "503"} <= set(responses), label
            if "{" in path:
                assert "404" in responses, label
            for status, response in responses.items():
                if status.startswith(("4", "5")):
                    schema = response["content"]["application/json"]["schema"]
                    assert "$ref" in schema, f"{label} {status} has no body model"
    commands = document["paths"]["/api/v1/vehicles/{vehicle_id}/commands"]["post"]
    assert {"409", "422", "429", "504"} <= set(commands["responses"])
    start = next(
        p for p in document["paths"]["/api/v1/events"]["get"]["parameters"] if p["name"] == "start"
    )
    forms = start["schema"]["anyOf"]
    assert {"type": "number", "minimum": 0, "maximum": 1e11} in forms
    assert {"type": "string", "format": "date-time"} in forms
    assert "inclusive" in start["description"]
