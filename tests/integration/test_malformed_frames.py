"""Frames the JSON parser itself chokes on (nesting past its recursion limit, integers past
the interpreter's digit limit) take the same bad-frame path as any other undecodable frame:
an error reply, counted, and the connection goes on."""

from __future__ import annotations

import json
from collections.abc import Callable

import pytest

from protocol.messages import CLIENT_WS_PATH, ProtocolError, agent_to_hub
from tests.support.agents import scripted_agent, telemetry_frame, wait_stored, websocket, ws_url
from tests.support.api import api_client

Enrol = Callable[[str], str]

UNPARSABLE = {
    "deep nesting": "[" * 30_000,
    "huge integer": '{"type": "ping", "nonce": ' + "9" * 5_000 + "}",
}


@pytest.mark.parametrize("frame", UNPARSABLE.values(), ids=UNPARSABLE.keys())
def test_decode_reports_every_unparsable_frame_as_bad(frame: str) -> None:
    with pytest.raises(ProtocolError) as refused:
        agent_to_hub.decode(frame)
    assert refused.value.code == "bad_frame"


def test_agent_socket_answers_unparsable_frames_and_goes_on(
    hub: str, enrol: Enrol, admin_token: str
) -> None:
    with scripted_agent(hub, "v1", enrol("v1")) as agent, api_client(hub, admin_token) as api:
        for frame in UNPARSABLE.values():
            agent.send(frame)
            reply = json.loads(agent.recv(timeout=5))
            assert reply["type"] == "error"
            assert reply["code"] == "bad_frame"
            assert "not valid JSON" in reply["message"]
        agent.send(telemetry_frame(0))
        wait_stored(api, "v1", 1)


def test_dashboard_socket_answers_unparsable_frames_and_goes_on(hub: str, admin_token: str) -> None:
    headers = {"Authorization": f"Bearer {admin_token}"}
    with websocket(ws_url(hub, CLIENT_WS_PATH), headers) as client:
        assert json.loads(client.recv(timeout=5))["type"] == "fleet"
        for frame in UNPARSABLE.values():
            client.send(frame)
            reply = json.loads(client.recv(timeout=5))
            assert (reply["type"], reply["code"]) == ("error", "bad_frame")
        client.send('{"type": "ping", "nonce": "after"}')
        assert json.loads(client.recv(timeout=5)) == {"type": "pong", "nonce": "after"}
