"""A group command costs what it does: unknown ids are refused as one answer, and each
vehicle reached counts in the caller's rate limit."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import httpx

from tests.conftest import ADMIN_PASSWORD, hub_settings
from tests.support.agents import scripted_agent
from tests.support.api import access_token, api_client
from tests.support.hub_server import running_hub


def _audit_entries(api: httpx.Client) -> int:
    return len(api.get("/api/v1/audit", params={"limit": 1000}).json()["entries"])


def test_unknown_vehicle_ids_are_refused_as_one_answer(
    hub: str, admin_api: httpx.Client, enrol: Callable[[str], str]
) -> None:
    with scripted_agent(hub, "g1", enrol("g1")):
        pass  # now a known vehicle, offline
    before = _audit_entries(admin_api)
    made_up = ["g1", *(f"ghost-{n}" for n in range(999))]
    response = admin_api.post(
        "/api/v1/fleet/commands", json={"vehicle_ids": made_up, "command": {"name": "land"}}
    )
    assert response.status_code == 422, response.text
    (detail,) = response.json()["detail"]
    assert detail["loc"] == ["body", "vehicle_ids"]
    assert detail["msg"].startswith("unknown vehicles: ghost-0, ghost-1")
    assert "and 989 more" in detail["msg"]
    assert _audit_entries(admin_api) == before  # nothing was sent, nothing to record


def test_the_selection_size_is_capped(admin_api: httpx.Client) -> None:
    too_many = [f"v{n}" for n in range(1001)]
    response = admin_api.post(
        "/api/v1/fleet/commands", json={"vehicle_ids": too_many, "command": {"name": "land"}}
    )
    assert response.status_code == 422
    assert response.json()["detail"][0]["loc"] == ["body", "vehicle_ids"]


def test_each_vehicle_reached_counts_in_the_rate_limit(
    tmp_path: Path,
) -> None:
    with running_hub(hub_settings(tmp_path, commands_per_second=3)) as hub:
        token = access_token(hub, "admin", ADMIN_PASSWORD)
        with api_client(hub, token) as admin:
            for vehicle in ("r1", "r2", "r3"):
                enrolled = admin.post(f"/api/v1/vehicles/{vehicle}/agent-tokens").json()
                with scripted_agent(hub, vehicle, enrolled["token"]):
                    pass  # known and offline: each answers 409 at once
            group = {"vehicle_ids": ["r1", "r2", "r3"], "command": {"name": "land"}}
            first = admin.post("/api/v1/fleet/commands", json=group)
            # Three commands in the last second already: the budget is spent.
            second = admin.post("/api/v1/fleet/commands", json=group)
    assert first.status_code == 200, first.text
    assert [r["status_code"] for r in first.json()["results"]] == [409, 409, 409]
    assert second.status_code == 429
    assert "too many commands" in second.json()["detail"]
