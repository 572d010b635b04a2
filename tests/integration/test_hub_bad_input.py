"""Bad input to the hub: each case gets a clear error, and everyone else keeps being served."""

from __future__ import annotations

import json
import logging
from collections.abc import Callable
from typing import Any

import httpx
import pytest
from websockets.exceptions import ConnectionClosed

from protocol.messages import (
    AGENT_WS_PATH,
    CLIENT_WS_PATH,
    MAX_FRAME_BYTES,
    CloseCode,
    encode,
)
from tests.support.agents import (
    close_code,
    scripted_agent,
    stored_count,
    telemetry_frame,
    wait_stored,
    websocket,
    ws_url,
)
from tests.support.api import api_client
from tests.support.hellos import agent_hello

Enrol = Callable[[str], str]


def test_unknown_vehicle_is_404(hub: str, enrol: Enrol, admin_token: str) -> None:
    with api_client(hub, admin_token) as api:
        for response in (
            api.get("/api/v1/vehicles/nope"),
            api.post("/api/v1/vehicles/nope/commands", json={"name": "arm"}),
            api.get("/api/v1/vehicles/nope/telemetry"),
        ):
            assert response.status_code == 404
            assert "nope" in response.json()["detail"]


def test_invalid_command_parameters_are_422_naming_the_field(
    hub: str, enrol: Enrol, admin_token: str
) -> None:
    with scripted_agent(hub, "v1", enrol("v1")), api_client(hub, admin_token) as api:
        too_high = api.post(
            "/api/v1/vehicles/v1/commands", json={"name": "takeoff", "altitude": 9000}
        )
        assert too_high.status_code == 422
        assert "altitude" in json.dumps(too_high.json()["detail"])

        unknown = api.post("/api/v1/vehicles/v1/commands", json={"name": "fly_to_moon"})
        assert unknown.status_code == 422
        assert "name" in json.dumps(unknown.json()["detail"])

        bad_mode = api.post(
            "/api/v1/vehicles/v1/commands", json={"name": "set_mode", "mode": "WARP"}
        )
        assert bad_mode.status_code == 422
        detail = bad_mode.json()["detail"][0]
        assert detail["loc"][-1] == "mode"
        assert "WARP" in detail["msg"]
        assert "GUIDED" in detail["msg"]


def test_start_after_end_is_422(hub: str, enrol: Enrol, admin_token: str) -> None:
    with scripted_agent(hub, "v1", enrol("v1")), api_client(hub, admin_token) as api:
        response = api.get("/api/v1/vehicles/v1/telemetry", params={"start": 200, "end": 100})
        assert response.status_code == 422
        assert "start" in json.dumps(response.json())


@pytest.mark.parametrize(
    ("headers", "reason"),
    [
        ({}, "missing agent token"),
        ({"Authorization": "Bearer wrong"}, "invalid or revoked agent token"),
    ],
)
def test_agent_with_bad_token_is_refused_and_logged(
    hub: str,
    admin_token: str,
    headers: dict[str, str],
    reason: str,
    caplog: pytest.LogCaptureFixture,
) -> None:
    caplog.set_level(logging.WARNING, logger="backend.realtime.agent_gateway")
    with websocket(ws_url(hub, AGENT_WS_PATH), headers) as socket:
        # The hub closes before reading anything, so the hello never counts.
        code, text = close_code(socket)
    assert code == CloseCode.UNAUTHORIZED
    assert reason in text
    assert any(reason in record.getMessage() for record in caplog.records)
    with api_client(hub, admin_token) as api:
        assert api.get("/api/v1/vehicles/intruder").status_code == 404


def test_bad_frames_get_error_replies_and_the_connection_survives(
    hub: str, enrol: Enrol, admin_token: str
) -> None:
    with scripted_agent(hub, "v1", enrol("v1")) as agent, api_client(hub, admin_token) as api:
        agent.send(telemetry_frame(0))
        agent.send("{not json")
        reply = json.loads(agent.recv(timeout=5))
        assert reply == {"type": "error", "code": "bad_frame", "message": reply["message"]}
        assert "not valid JSON" in reply["message"]

        agent.send(
            json.dumps({"type": "telemetry", "seq": 1, "time": 1.0, "state": {"lat": "north"}})
        )
        reply = json.loads(agent.recv(timeout=5))
        assert reply["code"] == "invalid_message"
        assert "state.lat" in reply["message"]

        agent.send(telemetry_frame(1))
        wait_stored(api, "v1", 2)  # the good frames before and after both stored


def test_oversized_frame_closes_only_that_agent(hub: str, enrol: Enrol, admin_token: str) -> None:
    with (
        scripted_agent(hub, "big", enrol("big")) as big,
        scripted_agent(hub, "good", enrol("good")) as good,
        api_client(hub, admin_token) as api,
    ):
        big.send(telemetry_frame(0))
        wait_stored(api, "big", 1)
        big.send("x" * (MAX_FRAME_BYTES + 1))
        code, _ = close_code(big)
        assert code == CloseCode.MESSAGE_TOO_BIG
        good.send(telemetry_frame(0))
        wait_stored(api, "good", 1)
        assert stored_count(api, "big") == 1  # what was accepted stays stored
        vehicles = {v["id"]: v for v in api.get("/api/v1/vehicles").json()}
        assert vehicles["good"]["connected"] is True
        assert vehicles["big"]["connected"] is False


def test_repeated_abuse_closes_the_connection(hub: str, enrol: Enrol, admin_token: str) -> None:
    with scripted_agent(hub, "noisy", enrol("noisy")) as agent:
        for _ in range(25):
            try:
                agent.send("garbage")
            except ConnectionClosed:
                break
        code, reason = close_code(agent)
    assert code == CloseCode.POLICY_VIOLATION
    assert "too many bad frames" in reason


def test_duplicate_telemetry_is_stored_once(hub: str, enrol: Enrol, admin_token: str) -> None:
    with scripted_agent(hub, "v1", enrol("v1")) as agent, api_client(hub, admin_token) as api:
        for seq in (0, 1, 1, 2, 0, 3):
            agent.send(telemetry_frame(seq))
        wait_stored(api, "v1", 4)
        page = api.get("/api/v1/vehicles/v1/telemetry", params={"start": 0}).json()
        assert [sample["seq"] for sample in page["samples"]] == [0, 1, 2, 3]


def test_client_bad_frame_gets_error_reply_and_feed_continues(
    hub: str, enrol: Enrol, admin_token: str
) -> None:
    with websocket(
        ws_url(hub, CLIENT_WS_PATH), {"Authorization": f"Bearer {admin_token}"}
    ) as client:
        assert json.loads(client.recv(timeout=5))["type"] == "fleet"
        client.send('{"type": "launch_missiles"}')
        reply: dict[str, Any] = json.loads(client.recv(timeout=5))
        assert reply["type"] == "error"
        assert reply["code"] == "invalid_message"
        client.send('{"type": "ping", "nonce": "n1"}')
        assert json.loads(client.recv(timeout=5)) == {"type": "pong", "nonce": "n1"}
        with scripted_agent(hub, "late", enrol("late")):
            update = json.loads(client.recv(timeout=5))
            while update["type"] == "events":  # the live event feed (link up) may come first
                update = json.loads(client.recv(timeout=5))
            assert update["type"] == "vehicles"
            assert [vehicle["id"] for vehicle in update["vehicles"]] == ["late"]


def test_revoked_agent_token_drops_the_live_agent(
    hub: str, admin_api: httpx.Client, enrol: Enrol
) -> None:
    token = enrol("rev")
    token_id = admin_api.get("/api/v1/agent-tokens", params={"vehicle_id": "rev"}).json()[0]["id"]
    with scripted_agent(hub, "rev", token) as agent:
        agent.send(telemetry_frame(0))
        assert admin_api.delete(f"/api/v1/agent-tokens/{token_id}").status_code == 204
        code, reason = close_code(agent)
    assert code == CloseCode.UNAUTHORIZED
    assert "revoked" in reason
    with websocket(ws_url(hub, AGENT_WS_PATH), {"Authorization": f"Bearer {token}"}) as again:
        assert close_code(again)[0] == CloseCode.UNAUTHORIZED


def test_agent_token_cannot_speak_for_another_vehicle(
    hub: str, admin_api: httpx.Client, enrol: Enrol
) -> None:
    token_a = enrol("alpha")
    enrol("bravo")
    headers = {"Authorization": f"Bearer {token_a}"}
    with websocket(ws_url(hub, AGENT_WS_PATH), headers) as socket:
        socket.send(encode(agent_hello("bravo", stream_id="s1")))
        code, reason = close_code(socket)
    assert code == CloseCode.FORBIDDEN
    assert "alpha" in reason
    assert "bravo" in reason
    assert admin_api.get("/api/v1/vehicles/bravo").status_code == 404
