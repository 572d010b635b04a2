"""Prometheus metrics at /metrics: for admins only, and counting what the hub refuses."""

from __future__ import annotations

import contextlib
import json

import httpx
from websockets.exceptions import ConnectionClosed
from websockets.sync.client import connect

from protocol.messages import AGENT_WS_PATH, CLIENT_WS_PATH
from tests.support.api import access_token
from tests.support.metrics import _metrics, _value


def test_metrics_need_an_admin(hub: str, admin_api: httpx.Client) -> None:
    assert httpx.get(f"{hub}/metrics").status_code == 401
    admin_api.post(
        "/api/v1/users",
        json={"username": "watcher", "password": "correct horse battery", "role": "viewer"},
    ).raise_for_status()
    viewer = access_token(hub, "watcher", "correct horse battery")
    response = httpx.get(f"{hub}/metrics", headers={"Authorization": f"Bearer {viewer}"})
    assert response.status_code == 403


def test_refused_frames_are_counted_by_surface(hub: str, admin_token: str) -> None:
    before = _metrics(hub, admin_token)
    client_series = 'gcs_rejected_frames_total{surface="client_ws"}'
    agent_series = 'gcs_rejected_frames_total{surface="agent_ws"}'
    headers = {"Authorization": f"Bearer {admin_token}"}
    with connect(
        hub.replace("http://", "ws://") + CLIENT_WS_PATH, additional_headers=headers
    ) as ws:
        assert json.loads(ws.recv(timeout=5))["type"] == "fleet"
        ws.send("not json")
        ws.send('{"type": "launch_missiles"}')
        replies = [json.loads(ws.recv(timeout=5)) for _ in range(2)]
        assert [reply["type"] for reply in replies] == ["error", "error"]
        after = _metrics(hub, admin_token)
        assert _value(after, 'gcs_connections{kind="dashboard"}') >= 1
    assert _value(after, client_series) == _value(before, client_series) + 2
    # An agent's first frame that is no hello: refused, and counted as the agent surface's.
    enrolled = httpx.post(f"{hub}/api/v1/vehicles/m1/agent-tokens", headers=headers).json()
    agent_headers = {"Authorization": f"Bearer {enrolled['token']}"}
    with (
        contextlib.suppress(ConnectionClosed),
        connect(
            hub.replace("http://", "ws://") + AGENT_WS_PATH, additional_headers=agent_headers
        ) as agent,
    ):
        agent.send('{"type": "ping", "nonce": "x"}')
        agent.recv(timeout=5)
    final = _metrics(hub, admin_token)
    assert _value(final, agent_series) == _value(before, agent_series) + 1
    assert _value(final, 'gcs_messages_in_total{surface="client_ws"}') >= 2
