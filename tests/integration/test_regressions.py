"""Defects found in review, each pinned by the scenario that showed it."""

from __future__ import annotations

import concurrent.futures
import json
from collections.abc import Callable

import httpx
import pytest

from backend.storage.flights import FlightTracker
from backend.storage.records import TelemetryEnvelope
from protocol.messages import CLIENT_WS_PATH, CloseCode, Telemetry, VehicleState
from tests.support.agents import close_code, scripted_agent, telemetry_frame, websocket
from tests.support.api import api_client
from tests.support.waiting import poll_until
from tests.support.watcher import FleetWatcher

Enrol = Callable[[str], str]


def _feed_url(hub: str) -> str:
    return hub.replace("http://", "ws://") + CLIENT_WS_PATH


def test_live_feed_needs_the_read_permission(
    hub: str, admin_api: httpx.Client, enrol: Enrol
) -> None:
    audit_only = admin_api.post(
        "/api/v1/auth/api-tokens", json={"name": "auditor", "scopes": ["audit"]}
    ).json()["token"]
    for token in (enrol("v1"), audit_only):  # an agent's token; a token without "read"
        with websocket(_feed_url(hub), {"Authorization": f"Bearer {token}"}) as feed:
            assert close_code(feed)[0] == CloseCode.FORBIDDEN


def test_revoking_a_token_ends_its_live_feed(hub: str, admin_api: httpx.Client) -> None:
    created = admin_api.post("/api/v1/auth/api-tokens", json={"name": "wall"}).json()
    with websocket(_feed_url(hub), {"Authorization": f"Bearer {created['token']}"}) as feed:
        assert json.loads(feed.recv(timeout=5))["type"] == "fleet"
        assert admin_api.delete(f"/api/v1/auth/api-tokens/{created['id']}").status_code == 204
        code, reason = close_code(feed)
    assert code == CloseCode.UNAUTHORIZED
    assert "revoked" in reason


def test_nan_and_oversized_numbers_are_refused_at_the_edge(
    hub: str, admin_api: httpx.Client, enrol: Enrol
) -> None:
    with scripted_agent(hub, "v1", enrol("v1")) as agent:
        for bad in (
            '{"type":"telemetry","seq":1,"time":NaN,"state":{}}',
            '{"type":"telemetry","seq":18446744073709551616,"time":1,"state":{}}',
            '{"type":"telemetry","seq":1,"time":1,"state":{"mode":"' + "M" * 40 + '"}}',
        ):
            agent.send(bad)
            assert json.loads(agent.recv(timeout=5))["code"] in ("bad_frame", "invalid_message")
        agent.send(telemetry_frame(2))
        poll_until(  # polling the store; the writer flushes every 0.25 s
            lambda: admin_api.get("/api/v1/health").json()["telemetry_written"] >= 1,
            10,
            "the writer to store a sample (it stopped?)",
            every_s=0.05,
        )


def test_a_reconnecting_agent_keeps_its_vehicle_online(
    hub: str, admin_token: str, enrol: Enrol
) -> None:
    token = enrol("v1")
    with scripted_agent(hub, "v1", token) as first, scripted_agent(hub, "v1", token):
        assert close_code(first)[0] == CloseCode.SUPERSEDED
        with FleetWatcher(hub, admin_token) as watcher:
            watcher.wait_until(lambda v: "v1" in v, 5, "the fleet snapshot")
            assert watcher.vehicles["v1"]["connected"] is True


def test_concurrent_password_guesses_hit_the_limit(hub: str) -> None:
    def guess(_: int) -> int:
        response = httpx.post(
            f"{hub}/api/v1/auth/login", json={"username": "admin", "password": "guess"}, timeout=30
        )
        return response.status_code

    with concurrent.futures.ThreadPoolExecutor(20) as pool:
        statuses = list(pool.map(guess, range(20)))
    assert statuses.count(401) <= 5
    assert statuses.count(429) >= 15


def test_long_agent_text_keeps_the_audit_log_readable(
    hub: str, admin_api: httpx.Client, enrol: Enrol, admin_token: str
) -> None:
    with scripted_agent(hub, "v1", enrol("v1")):
        response = admin_api.post(
            "/api/v1/vehicles/v1/commands",
            json={"name": "set_mode", "mode": "X" * 32},  # unknown mode: a long refusal
        )
        assert response.status_code == 422
    with api_client(hub, admin_token) as api:
        page = api.get("/api/v1/audit")
    assert page.status_code == 200
    assert page.json()["entries"]


def test_a_flight_open_at_restart_closes_on_the_first_disarmed_sample() -> None:
    tracker = FlightTracker(open_flights={"v1": 7})  # a hub restarted mid-flight
    state = VehicleState(armed=False, mode="LAND")
    plan = tracker.plan([TelemetryEnvelope("v1", "s", Telemetry(seq=5, time=9.0, state=state))])
    assert [type(t).__name__ for t in plan.transitions] == ["FlightClosed"]


@pytest.mark.parametrize(
    "path",
    [
        "/api/v1/flights/99999999999999999999",
        "/api/v1/events?before_id=99999999999999999999",
        "/api/v1/vehicles/v1/telemetry?end=0001-01-01T00:00:00",
    ],
)
def test_out_of_range_numbers_are_422_not_500(
    hub: str, admin_api: httpx.Client, enrol: Enrol, path: str
) -> None:
    with scripted_agent(hub, "v1", enrol("v1")):
        assert admin_api.get(path).status_code == 422
