"""A live socket (the dashboard's feed, the 3D view's relay) lasts no longer than the token
that opened it."""

from __future__ import annotations

import json
import time
from pathlib import Path

import pytest
from websockets.exceptions import ConnectionClosed
from websockets.sync.client import ClientConnection, connect

from protocol.messages import CLIENT_WS_PATH, CloseCode
from tests.conftest import ADMIN_PASSWORD, hub_settings
from tests.support.agents import scripted_agent, telemetry_frame
from tests.support.api import access_token
from tests.support.hub_server import running_hub
from tests.viz_wire import SUBPROTOCOL

TOKEN_TTL_S = 3.0


def test_a_dashboard_socket_closes_with_4401_when_its_token_expires(tmp_path: Path) -> None:
    # The agent's token is provisioned, so that no request spends the short token's life
    # (on a loaded machine, enrolling through the API could outlive it).
    agent_token = "t" * 32
    settings = hub_settings(
        tmp_path, access_token_ttl_s=TOKEN_TTL_S, agent_tokens=f"v1={agent_token}"
    )
    with running_hub(settings) as base:
        token = access_token(base, "admin", ADMIN_PASSWORD)
        opened = time.time()
        url = base.replace("http://", "ws://") + CLIENT_WS_PATH
        headers = {"Authorization": f"Bearer {token}"}
        with (
            scripted_agent(base, "v1", agent_token) as agent,
            connect(url, additional_headers=headers) as feed,
        ):
            assert json.loads(feed.recv(timeout=5))["type"] == "fleet"
            sent = 0

            def follow_while_reporting() -> None:
                """The vehicle keeps reporting and the feed passes it on, until it ends."""
                nonlocal sent
                give_up = time.monotonic() + TOKEN_TTL_S + 5
                while time.monotonic() < give_up:
                    agent.send(telemetry_frame(sent))
                    sent += 1
                    feed.recv(timeout=TOKEN_TTL_S + 5)

            with pytest.raises(ConnectionClosed) as closed:
                follow_while_reporting()
        ended = time.time()
    assert closed.value.rcvd is not None
    assert closed.value.rcvd.code == CloseCode.UNAUTHORIZED
    assert "expired" in closed.value.rcvd.reason
    assert sent > 1  # updates did flow until then
    assert ended - opened >= TOKEN_TTL_S - 0.5  # not before the token's lifetime


def test_the_3d_views_socket_closes_with_4401_when_its_token_expires(tmp_path: Path) -> None:
    """The other socket a user's token opens: the relay to the 3D scene under /viz/."""
    with running_hub(
        hub_settings(tmp_path, access_token_ttl_s=TOKEN_TTL_S, viz_enabled=True)
    ) as base:
        token = access_token(base, "admin", ADMIN_PASSWORD)
        opened = time.time()
        url = base.replace("http://", "ws://") + "/viz"
        headers = {"Authorization": f"Bearer {token}"}
        frames = 0

        def watch(view: ClientConnection) -> None:
            """The scene's frames, until the relay ends."""
            nonlocal frames
            while True:
                view.recv(timeout=TOKEN_TTL_S + 5)
                frames += 1

        view = connect(url, subprotocols=[SUBPROTOCOL], additional_headers=headers)  # type: ignore[list-item]
        with view, pytest.raises(ConnectionClosed) as closed:
            watch(view)
        ended = time.time()
    assert closed.value.rcvd is not None
    assert closed.value.rcvd.code == CloseCode.UNAUTHORIZED
    assert "expired" in closed.value.rcvd.reason
    assert frames >= 1  # the scene did reach the viewer until then
    assert ended - opened >= TOKEN_TTL_S - 0.5  # not before the token's lifetime
