"""Every route and every WebSocket message type, for every role: allowed or refused.

The routes are enumerated from the running app, so a new route or message type without a
policy fails here.
"""

from __future__ import annotations

import json
import re
import typing
import uuid
from collections.abc import Callable
from typing import Any

import httpx
import pytest
from websockets.exceptions import ConnectionClosed
from websockets.sync.client import connect

from backend.api.security import PERMISSION_KEY
from backend.auth.policy import (
    AGENT_MESSAGE_PERMISSIONS,
    CLIENT_MESSAGE_PERMISSIONS,
    PUBLIC,
    ROLE_PERMISSIONS,
    Permission,
    Role,
)
from protocol.messages import AGENT_WS_PATH, CLIENT_WS_PATH, AgentToHub, ClientToHub, CloseCode
from tests.support.api import access_token

PASSWORD = "correct horse battery"


def _message_types(union: Any) -> set[str]:
    members = typing.get_args(typing.get_args(union)[0]) or (typing.get_args(union)[0],)
    return {member.model_fields["type"].default for member in members}


def _operations(schema: dict[str, Any]) -> list[tuple[str, str, str]]:
    return [
        (method.upper(), path, operation[PERMISSION_KEY])
        for path, item in schema["paths"].items()
        for method, operation in item.items()
    ]


def _concrete(path: str) -> str:
    values = {
        "vehicle_id": "ghost",
        "username": "nobody",
        "token_id": "999999",
        "flight_id": "999999",
        "tlog_id": "999999",
        "format": "csv",
        "param": "WPNAV_SPEED",
        "survey_id": "0123456789abcdef",
        "formation_id": "0123456789abcdef",
        "viewer_id": "999999",
        "photo_id": "ghost-1-00001",
        "kind": "tif",  # a mosaic's export
        "z": "1",  # a mosaic's tile
        "x": "0",
        "y": "0",
    }
    return re.sub(r"\{(\w+)\}", lambda match: values[match.group(1)], path)


@pytest.fixture
def users(hub: str, admin_api: httpx.Client) -> dict[str, str]:
    """One user per role; returns role -> username."""
    created = {}
    for role in Role:
        name = f"{role.value}-{uuid.uuid4().hex[:6]}"
        response = admin_api.post(
            "/api/v1/users", json={"username": name, "password": PASSWORD, "role": role.value}
        )
        assert response.status_code == 201, response.text
        created[role.value] = name
    return created


def test_every_route_declares_a_permission(hub: str) -> None:
    schema = httpx.get(f"{hub}/openapi.json").json()
    for path, item in schema["paths"].items():
        for method, operation in item.items():
            assert PERMISSION_KEY in operation, f"{method.upper()} {path} has no policy"
            assert operation[PERMISSION_KEY] in {PUBLIC, *Permission}


def test_every_route_allows_exactly_the_roles_it_should(
    hub: str, users: dict[str, str], enrol: Callable[[str], str]
) -> None:
    operations = _operations(httpx.get(f"{hub}/openapi.json").json())
    assert len(operations) >= 20
    agent_token = enrol("ghost")
    callers: dict[str, Callable[[], dict[str, str]]] = {
        "anonymous": dict,
        # An agent token speaks for its vehicle (socket, .tlog upload), and does nothing else.
        "agent": lambda: {"Authorization": f"Bearer {agent_token}"},
        **{
            role: (
                lambda name=name: {"Authorization": f"Bearer {access_token(hub, name, PASSWORD)}"}
            )
            for role, name in users.items()
        },
    }
    failures = []
    # One token per caller, made again after a route that ends the token it is given
    # (logout): a login per call hashed a password per call, minutes of the suite.
    tokens: dict[str, dict[str, str]] = {}
    with httpx.Client(base_url=hub, timeout=30) as client:
        for method, path, permission in operations:
            for caller, headers in callers.items():
                if caller not in tokens:
                    tokens[caller] = headers()
                response = client.request(method, _concrete(path), headers=tokens[caller], json={})
                if path.endswith("/logout"):
                    tokens.pop(caller)
                if permission == PUBLIC:
                    expected_refusal = None
                elif caller == "anonymous":
                    expected_refusal = 401
                elif caller == "agent":
                    expected_refusal = None if permission == Permission.AGENT else 403
                elif Permission(permission) in ROLE_PERMISSIONS[Role(caller)]:
                    expected_refusal = None
                else:
                    expected_refusal = 403
                refused = response.status_code if response.status_code in (401, 403) else None
                if refused != expected_refusal:
                    failures.append(
                        f"{caller} {method} {path}: got {response.status_code}, "
                        f"expected {expected_refusal or 'allowed'}"
                    )
    assert failures == []


def test_every_websocket_message_type_has_a_policy() -> None:
    assert set(CLIENT_MESSAGE_PERMISSIONS) == _message_types(ClientToHub)
    assert set(AGENT_MESSAGE_PERMISSIONS) == _message_types(AgentToHub)


def test_client_feed_needs_a_login_and_serves_every_role(hub: str, users: dict[str, str]) -> None:
    url = hub.replace("http://", "ws://") + CLIENT_WS_PATH
    with pytest.raises(ConnectionClosed) as closed, connect(url) as anonymous:
        anonymous.recv(timeout=5)
    assert closed.value.rcvd is not None
    assert closed.value.rcvd.code == CloseCode.UNAUTHORIZED
    for name in users.values():
        headers = {"Authorization": f"Bearer {access_token(hub, name, PASSWORD)}"}
        with connect(url, additional_headers=headers) as feed:
            assert json.loads(feed.recv(timeout=5))["type"] == "fleet"
            # Every message a reader may send, each well formed, is served for every role;
            # the COMMAND ones (control, manual) are tested in tests/integration/manual_control/.
            for message_type, permission in CLIENT_MESSAGE_PERMISSIONS.items():
                if permission is not Permission.READ:
                    continue
                feed.send(json.dumps(_READ_SAMPLES[message_type]))
                assert json.loads(feed.recv(timeout=5))["type"] != "error"


# A valid message of each type that needs only READ.
_READ_SAMPLES: dict[str, dict[str, Any]] = {
    "ping": {"type": "ping", "nonce": "n1"},
    "subscribe_scans": {"type": "subscribe_scans", "vehicle_id": "V1"},
    "unsubscribe_scans": {"type": "unsubscribe_scans", "vehicle_id": "V1"},
    "subscribe_map": {"type": "subscribe_map", "layers": ["obstacles"]},
    "unsubscribe_map": {"type": "unsubscribe_map", "layers": ["obstacles"]},
}


def test_every_read_message_has_a_sample() -> None:
    reads = {t for t, p in CLIENT_MESSAGE_PERMISSIONS.items() if p is Permission.READ}
    assert reads == set(_READ_SAMPLES)


def test_user_tokens_cannot_connect_as_agents(hub: str, users: dict[str, str]) -> None:
    token = access_token(hub, users["admin"], PASSWORD)
    url = hub.replace("http://", "ws://") + AGENT_WS_PATH
    with (
        pytest.raises(ConnectionClosed) as closed,
        connect(url, additional_headers={"Authorization": f"Bearer {token}"}) as socket,
    ):
        socket.recv(timeout=5)
    assert closed.value.rcvd is not None
    assert closed.value.rcvd.code == CloseCode.UNAUTHORIZED


def test_websocket_from_a_foreign_origin_is_refused(hub: str, admin_token: str) -> None:
    url = hub.replace("http://", "ws://") + CLIENT_WS_PATH
    headers = {"Authorization": f"Bearer {admin_token}", "Origin": "https://evil.example"}
    with pytest.raises(ConnectionClosed) as closed, connect(url, additional_headers=headers) as s:
        s.recv(timeout=5)
    assert closed.value.rcvd is not None
    assert closed.value.rcvd.code == CloseCode.FORBIDDEN
    assert "evil.example" in closed.value.rcvd.reason
