"""The audit log as an integrator reads it: each entry names the token used, the actions
are a documented enum, a wrong filter is refused, and it pages like the other lists."""

from __future__ import annotations

import re
from collections.abc import Callable
from pathlib import Path
from typing import Any

import httpx

from backend.audit import AuditAction
from tests.conftest import ADMIN_PASSWORD, hub_settings
from tests.support.agents import scripted_agent
from tests.support.api import access_token, api_client
from tests.support.hub_server import running_hub
from tests.support.waiting import poll_until


def test_an_entry_names_the_api_token_that_acted(
    hub: str, admin_api: httpx.Client, enrol: Callable[[str], str]
) -> None:
    created = admin_api.post(
        "/api/v1/auth/api-tokens", json={"name": "ci-bot", "scopes": ["read", "command"]}
    ).json()
    with scripted_agent(hub, "v1", enrol("v1")):
        pass  # known and offline: the command is refused (409) and audited
    headers = {"Authorization": f"Bearer {created['token']}"}
    sent = httpx.post(f"{hub}/api/v1/vehicles/v1/commands", json={"name": "land"}, headers=headers)
    assert sent.status_code == 409, sent.text
    admin_api.post("/api/v1/vehicles/v1/commands", json={"name": "land"})

    entries = admin_api.get("/api/v1/audit", params={"action": "command"}).json()["entries"]
    by_admin_itself, by_token = entries  # newest first
    assert by_token["actor"] == "admin"
    assert by_token["token"] == "ci-bot"
    assert by_token["token_kind"] == "api"
    assert by_token["token_id"] == created["id"]
    assert by_admin_itself["actor"] == "admin"
    assert by_admin_itself["token"] is None
    assert by_admin_itself["token_kind"] == "access"
    enrolment = admin_api.get("/api/v1/audit", params={"action": "agent_token.create"}).json()
    assert enrolment["entries"][0]["token_kind"] == "access"


def test_the_actions_are_an_enum_in_the_openapi_document(hub: str) -> None:
    document = httpx.get(f"{hub}/openapi.json").json()
    schemas = document["components"]["schemas"]
    assert sorted(schemas["AuditAction"]["enum"]) == sorted(action.value for action in AuditAction)
    record = schemas["AuditRecord"]["properties"]
    assert record["action"] == {"$ref": "#/components/schemas/AuditAction"}
    assert {"token", "token_kind", "token_id"} <= set(record)
    assert "next_before_id" in schemas["AuditPage"]["required"]


def test_an_unknown_action_or_filter_is_refused_naming_the_valid_ones(
    admin_api: httpx.Client,
) -> None:
    wrong_action = admin_api.get("/api/v1/audit", params={"action": "commands"})
    assert wrong_action.status_code == 422
    (problem,) = wrong_action.json()["detail"]
    assert problem["loc"] == ["query", "action"]
    assert "'command'" in problem["msg"]
    assert "'token.create'" in problem["msg"]

    wrong_filter = admin_api.get("/api/v1/audit", params={"user": "admin"})
    assert wrong_filter.status_code == 422
    (problem,) = wrong_filter.json()["detail"]
    assert problem["loc"] == ["query", "user"]
    assert problem["msg"] == (
        "unknown filter 'user'; valid filters: actor, action, target, since, until, "
        "before_id, limit"
    )


def test_the_audit_log_pages_with_next_before_id(admin_api: httpx.Client) -> None:
    for name in ("a", "b", "c", "d", "e"):
        created = admin_api.post("/api/v1/auth/api-tokens", json={"name": name})
        assert created.status_code == 201
    seen: list[str] = []
    params: dict[str, str | int] = {"action": "token.create", "limit": 2}
    pages = 0
    while True:
        page = admin_api.get("/api/v1/audit", params=params).json()
        pages += 1
        seen += [entry["target"] for entry in page["entries"]]
        if page["next_before_id"] is None:
            break
        params["before_id"] = page["next_before_id"]
    assert seen == ["e", "d", "c", "b", "a"]
    assert pages == 3


def test_the_security_page_documents_every_action() -> None:
    page = (Path(__file__).parents[2] / "docs" / "security.md").read_text()
    documented = set(re.findall(r"^\| `([a-z_.]+)` \|", page, flags=re.MULTILINE))
    assert {action.value for action in AuditAction} <= documented


def test_a_flood_of_refusals_leaves_one_row_and_then_its_count(tmp_path: Path) -> None:
    """A viewer refused in a loop, across many vehicle ids, writes one row per route and
    reason per interval, and one more with the count: a bounded trace naming who and what."""
    settings = hub_settings(tmp_path, audit_denial_interval_s=1.0)
    with (
        running_hub(settings) as hub,
        api_client(hub, access_token(hub, "admin", ADMIN_PASSWORD)) as admin,
    ):
        created = admin.post(
            "/api/v1/users",
            json={"username": "victor", "password": "correct horse battery", "role": "viewer"},
        )
        assert created.status_code == 201, created.text
        with api_client(hub, access_token(hub, "victor", "correct horse battery")) as viewer:
            for index in range(60):
                refused = viewer.post(f"/api/v1/vehicles/v{index}/commands", json={"name": "arm"})
                assert refused.status_code == 403

        def denials() -> list[dict[str, Any]]:
            entries = admin.get("/api/v1/audit", params={"actor": "victor"}).json()["entries"]
            return [entry for entry in entries if entry["outcome"] == "denied"]

        counted = poll_until(
            lambda: [entry for entry in denials() if "repeated" in entry["detail"]],
            10,
            "the count of the refusals after the first",
        )
        rows = denials()
        assert len(rows) == 2, rows
        (count,) = counted
        assert count["detail"]["repeated"] == 59
        first = next(entry for entry in rows if "repeated" not in entry["detail"])
        assert first["target"] == "POST /api/v1/vehicles/v0/commands"
        assert "command" in first["detail"]["reason"]
