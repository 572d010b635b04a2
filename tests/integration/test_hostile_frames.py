"""Fuzzed frames over real WebSockets to a real hub (the decoders' fuzz strategies from
tests/fuzz/test_decoders_fuzz.py): each bad frame is answered with an error, in order, and
counted on ``gcs_rejected_frames_total{surface}``; past the bad-frame limit the connection
is closed with a clear code, and a new one is served. Deeply nested JSON (100,000 levels)
gets a clear answer on every JSON route and on both sockets, never a 500."""

from __future__ import annotations

import json
from collections.abc import Callable
from typing import Any

import httpx
import pytest
from hypothesis import HealthCheck, Phase, given, settings
from hypothesis import strategies as st
from prometheus_client import REGISTRY
from websockets.exceptions import ConnectionClosed

from backend.observability.metrics import Surface
from protocol.messages import (
    AGENT_WS_PATH,
    CLIENT_WS_PATH,
    CloseCode,
    Decoder,
    ProtocolError,
    agent_to_hub,
    client_to_hub,
)
from tests.support.agents import (
    close_code,
    scripted_agent,
    telemetry_frame,
    wait_stored,
    websocket,
    ws_url,
)
from tests.support.api import api_client
from tests.support.frames import AGENT_FRAMES, CLIENT_FRAMES, any_frames, scan_frames

Enrol = Callable[[str], str]
MAX_BAD_FRAMES = 20  # the hub's default (settings.max_bad_frames)
DEEP = 100_000


def rejected(surface: Surface) -> float:
    value = REGISTRY.get_sample_value("gcs_rejected_frames_total", {"surface": surface})
    return value or 0.0


def _refused_by(decoder: Decoder[Any]) -> Callable[[str | bytes], bool]:
    def refused(frame: str | bytes) -> bool:
        try:
            decoder.decode(frame)
        except ProtocolError:
            return True
        return False

    return refused


LIVE = settings(
    max_examples=1,  # one list of frames: the hub's own state carries from frame to frame
    deadline=None,
    derandomize=True,
    phases=[Phase.generate],  # no shrinking: each attempt is a live run
    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow],
)


@LIVE
@given(
    frames=st.lists(
        # as text: a binary frame on the agent's socket is a scan
        any_frames(AGENT_FRAMES)
        .map(lambda f: f.decode("utf-8", "replace") if isinstance(f, bytes) else f)
        .filter(_refused_by(agent_to_hub)),
        min_size=45,
        max_size=45,
        unique=True,
    ),
    scans=st.lists(scan_frames(), min_size=10, max_size=10, unique=True),
)
def test_fuzzed_agent_frames_are_answered_counted_and_the_hub_goes_on(
    hub: str, enrol: Enrol, admin_token: str, frames: list[str], scans: list[bytes]
) -> None:
    token = enrol("fz")
    before, scans_before = rejected("agent_ws"), rejected("agent_scan")
    replies, closes = 0, 0
    pending = ["", *frames]  # an empty frame is a frame, not the end of the session
    scans = [b"", *scans]
    with api_client(hub, admin_token) as api:
        while pending:
            with scripted_agent(hub, "fz", token) as agent:
                for scan in scans:  # binary frames: scans, refused (no answer for each)
                    agent.socket.send(scan)
                while pending:
                    agent.send(pending.pop(0))
                    reply = json.loads(agent.recv(timeout=5))
                    while reply["message"].startswith("scan:"):  # at most one a second
                        reply = json.loads(agent.recv(timeout=5))
                    assert reply["type"] == "error", reply
                    assert reply["code"] in ("bad_frame", "invalid_message"), reply
                    replies += 1
                    if replies % MAX_BAD_FRAMES == 0:
                        too_many = json.loads(agent.recv(timeout=5))
                        assert too_many["code"] == "too_many_errors"
                        assert close_code(agent.socket)[0] == CloseCode.POLICY_VIOLATION
                        closes += 1
                        break
                else:
                    agent.send(telemetry_frame(0))  # a good frame after the junk is stored
                    wait_stored(api, "fz", 1)
    assert replies == len(frames) + 1
    assert closes == (len(frames) + 1) // MAX_BAD_FRAMES
    assert rejected("agent_ws") - before == len(frames) + 1
    # every scan refused and counted (the first socket's scans before its first reply)
    assert rejected("agent_scan") - scans_before >= len(scans)


@LIVE
@given(
    frames=st.lists(
        any_frames(CLIENT_FRAMES).filter(_refused_by(client_to_hub)),
        min_size=30,
        max_size=30,
        unique=True,
    )
)
def test_fuzzed_dashboard_frames_are_answered_counted_and_the_feed_goes_on(
    hub: str, admin_token: str, frames: list[str | bytes]
) -> None:
    before = rejected("client_ws")
    headers = {"Authorization": f"Bearer {admin_token}"}
    replies = 0
    pending = list(frames)
    while pending:
        with websocket(ws_url(hub, CLIENT_WS_PATH), headers) as client:
            assert json.loads(client.recv(timeout=5))["type"] == "fleet"
            while pending:
                frame = pending.pop(0)
                client.send(frame)
                reply = json.loads(client.recv(timeout=5))
                while reply["type"] != "error":  # a live push (events) may come between
                    reply = json.loads(client.recv(timeout=5))
                assert reply["code"] in ("bad_frame", "invalid_message"), reply
                replies += 1
                if replies % MAX_BAD_FRAMES == 0:
                    assert close_code(client)[0] == CloseCode.POLICY_VIOLATION
                    break
            else:
                client.send('{"type": "ping", "nonce": "after"}')
                assert json.loads(client.recv(timeout=5)) == {"type": "pong", "nonce": "after"}
    assert replies == len(frames)
    assert rejected("client_ws") - before == len(frames)


NESTED = {
    "arrays": "[" * DEEP + "]" * DEEP,
    "objects": '{"a": ' * DEEP + "1" + "}" * DEEP,
}


@pytest.mark.parametrize("body", NESTED.values(), ids=NESTED.keys())
def test_100k_nested_json_is_a_4xx_on_every_json_route(
    hub: str, admin_token: str, body: str
) -> None:
    with api_client(hub, admin_token) as api:
        document = api.get("/openapi.json").json()
        answered: dict[str, int] = {}
        for path, operations in document["paths"].items():
            for method, operation in operations.items():
                content = operation.get("requestBody", {}).get("content", {})
                if "application/json" not in content:
                    continue
                url = path.replace("{", "").replace("}", "")  # ids that are plain words
                response = api.request(
                    method, url, content=body, headers={"Content-Type": "application/json"}
                )
                answered[f"{method.upper()} {path}"] = response.status_code
    assert len(answered) > 15, answered  # the routes were found
    failures = {route: code for route, code in answered.items() if not 400 <= code < 500}
    assert not failures, failures


def test_100k_nested_json_over_a_websocket_closes_it_too_big(
    hub: str, enrol: Enrol, admin_token: str
) -> None:
    """100,000 levels are 200 KB: over the frame limit, closed with 1009 before parsing;
    the most nesting that fits is an undecodable frame like any other."""
    headers = {"Authorization": f"Bearer {admin_token}"}
    fits = "[" * 30_000 + "]" * 30_000
    with websocket(ws_url(hub, CLIENT_WS_PATH), headers) as client:
        assert json.loads(client.recv(timeout=5))["type"] == "fleet"
        client.send(fits)
        assert json.loads(client.recv(timeout=5))["code"] == "bad_frame"
        client.send(NESTED["arrays"])
        assert close_code(client)[0] == CloseCode.MESSAGE_TOO_BIG
    before = rejected("agent_ws")
    with scripted_agent(hub, "deep", enrol("deep")) as agent:
        agent.send(fits)
        assert json.loads(agent.recv(timeout=5))["code"] == "bad_frame"
        agent.send(NESTED["objects"])
        assert close_code(agent.socket)[0] == CloseCode.MESSAGE_TOO_BIG
    # The server's WebSocket layer closes an oversized frame before the hub reads it
    # (uvicorn's ws_max_size), so only the undecodable one is counted.
    assert rejected("agent_ws") - before == 1
    with pytest.raises(ConnectionClosed):
        agent.socket.send("{}")
    assert httpx.get(f"{hub}/api/v1/health").status_code == 200


def test_a_bad_first_frame_is_closed_as_a_bad_hello_and_counted(hub: str, enrol: Enrol) -> None:
    headers = {"Authorization": f"Bearer {enrol('hi')}"}
    for frame in ("", "[" * 30_000, '{"type": "hello", "protocol": "x"}'):
        before = rejected("agent_ws")
        with websocket(ws_url(hub, AGENT_WS_PATH), headers) as socket:
            socket.send(frame)
            code, reason = close_code(socket)
        assert code == CloseCode.BAD_HELLO, (frame[:40], code, reason)
        assert "first frame must be a hello" in reason
        assert rejected("agent_ws") - before == 1
