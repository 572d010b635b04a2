"""A token's scopes, as a client meets them: a refusal blames what is short (the token's
scopes or the role), token creation names scopes as they are written, and the OpenAPI
document lists the scopes."""

from __future__ import annotations

import httpx
import pytest
from websockets.exceptions import ConnectionClosed
from websockets.sync.client import connect

from protocol.messages import CLIENT_WS_PATH, CloseCode
from tests.conftest import ADMIN_PASSWORD

SCOPES = ["admin", "audit", "command", "read"]


def _token_form(hub: str, scope: str) -> httpx.Response:
    form = {"username": "admin", "password": ADMIN_PASSWORD, "scope": scope}
    return httpx.post(f"{hub}/api/v1/auth/token", data=form, timeout=30)


def test_a_read_only_token_is_refused_for_its_scopes_not_its_role(
    hub: str, admin_api: httpx.Client
) -> None:
    created = admin_api.post(
        "/api/v1/auth/api-tokens", json={"name": "wall-display", "scopes": ["read"]}
    )
    assert created.status_code == 201, created.text
    headers = {"Authorization": f"Bearer {created.json()['token']}"}
    refused = httpx.post(
        f"{hub}/api/v1/vehicles/v1/commands", json={"name": "land"}, headers=headers
    )
    assert refused.status_code == 403
    detail = refused.json()["detail"]
    assert detail.startswith("this token 'wall-display' lacks the 'command' permission")
    assert "its scopes are 'read'" in detail
    assert "(admin)" not in detail


def test_a_viewer_is_refused_for_its_role(hub: str, admin_api: httpx.Client) -> None:
    user = {"username": "vic", "password": "correct horse battery", "role": "viewer"}
    assert admin_api.post("/api/v1/users", json=user).status_code == 201
    form = {"username": "vic", "password": user["password"]}
    token = httpx.post(f"{hub}/api/v1/auth/token", data=form).json()["access_token"]
    refused = httpx.post(
        f"{hub}/api/v1/vehicles/v1/commands",
        json={"name": "land"},
        headers={"Authorization": f"Bearer {token}"},
    )
    assert refused.status_code == 403
    assert refused.json()["detail"] == "vic (viewer role) lacks the 'command' permission"


def test_creating_a_token_names_the_scopes_it_cannot_grant(
    hub: str, admin_api: httpx.Client
) -> None:
    narrow = admin_api.post("/api/v1/auth/api-tokens", json={"name": "ro", "scopes": ["read"]})
    headers = {"Authorization": f"Bearer {narrow.json()['token']}"}
    wider = httpx.post(
        f"{hub}/api/v1/auth/api-tokens",
        json={"name": "grab", "scopes": ["read", "admin"]},
        headers=headers,
    )
    assert wider.status_code == 403
    detail = wider.json()["detail"]
    assert detail.startswith("cannot grant the scopes 'admin':")
    assert "Permission" not in detail
    assert "<" not in detail


def test_an_unknown_scope_is_named_with_the_valid_ones(hub: str) -> None:
    refused = _token_form(hub, "read write")
    assert refused.status_code == 422, refused.text
    (problem,) = refused.json()["detail"]
    assert problem["loc"] == ["body", "scope"]
    assert problem["msg"] == (
        "unknown scope 'write'; valid scopes: 'admin', 'audit', 'command', 'read'"
    )
    granted = _token_form(hub, "read audit")
    assert granted.status_code == 200, granted.text


@pytest.mark.parametrize("scope", ["agent", "write"])
def test_an_api_token_s_scope_error_offers_only_what_can_be_granted(
    admin_api: httpx.Client, scope: str
) -> None:
    """`agent` belongs to agent tokens, which enrolment issues: it is no scope of a
    user's token, so it is refused as unknown and not offered among the valid ones."""
    refused = admin_api.post(
        "/api/v1/auth/api-tokens", json={"name": "integration", "scopes": ["read", scope]}
    )
    assert refused.status_code == 422, refused.text
    (problem,) = refused.json()["detail"]
    assert problem["loc"] == ["body", "scopes", 1]
    assert problem["msg"] == "Input should be 'read', 'command', 'audit' or 'admin'"
    document = admin_api.get("/openapi.json").json()
    body = document["components"]["schemas"]["ApiTokenRequest"]["properties"]["scopes"]
    (listed,) = [option for option in body["anyOf"] if option.get("type") == "array"]
    assert sorted(listed["items"]["enum"]) == SCOPES


def test_user_scope_names_the_scopes_of_the_security_scheme() -> None:
    from typing import get_args

    from backend.auth.policy import USER_SCOPES, UserScope

    assert sorted(get_args(UserScope)) == sorted(scope.value for scope in USER_SCOPES)


def test_the_openapi_security_scheme_lists_the_scopes(hub: str) -> None:
    document = httpx.get(f"{hub}/openapi.json").json()
    (scheme,) = document["components"]["securitySchemes"].values()
    flow = scheme["flows"]["password"]
    assert flow["tokenUrl"] == "/api/v1/auth/token"
    assert sorted(flow["scopes"]) == SCOPES
    assert all(flow["scopes"].values())
    commands = document["paths"]["/api/v1/vehicles/{vehicle_id}/commands"]["post"]
    assert commands["security"] == [{"OAuth2PasswordBearer": ["command"]}]


def test_a_long_refusal_still_closes_the_live_feed_with_its_code(
    hub: str, admin_api: httpx.Client
) -> None:
    name = "a-display-with-a-long-name-" + "x" * 100  # the refusal is over 123 bytes
    created = admin_api.post("/api/v1/auth/api-tokens", json={"name": name, "scopes": ["audit"]})
    headers = {"Authorization": f"Bearer {created.json()['token']}"}
    url = hub.replace("http", "ws", 1) + CLIENT_WS_PATH
    with connect(url, additional_headers=headers) as feed, pytest.raises(ConnectionClosed) as end:
        feed.recv(timeout=5)
    assert end.value.rcvd is not None
    assert end.value.rcvd.code == CloseCode.FORBIDDEN
    assert end.value.rcvd.reason.startswith(f"this token '{name[:40]}")
    assert end.value.rcvd.reason.endswith("…")
