"""A refused live feed says how to get in: the close reason is all a script sees."""

from __future__ import annotations

import pytest
from websockets.exceptions import ConnectionClosed
from websockets.sync.client import connect

from protocol.messages import CLIENT_WS_PATH, CloseCode


def _refusal(hub: str, headers: dict[str, str]) -> tuple[int, str]:
    url = hub.replace("http://", "ws://") + CLIENT_WS_PATH
    with (
        pytest.raises(ConnectionClosed) as closed,
        connect(url, additional_headers=headers) as feed,
    ):
        feed.recv(timeout=5)
    assert closed.value.rcvd is not None
    return closed.value.rcvd.code, closed.value.rcvd.reason


def test_without_a_credential_the_reason_says_what_to_send(hub: str) -> None:
    code, reason = _refusal(hub, {})
    assert code == CloseCode.UNAUTHORIZED
    assert "Authorization: Bearer <token>" in reason
    assert "session cookie" in reason
    assert "docs/websockets.md" in reason
    assert len(reason.encode()) <= 123  # what a close frame can carry


def test_with_a_bad_token_the_reason_says_to_log_in_again(hub: str) -> None:
    code, reason = _refusal(hub, {"Authorization": "Bearer not-a-token"})
    assert code == CloseCode.UNAUTHORIZED
    assert reason == "the token is invalid, expired or revoked: log in again"
