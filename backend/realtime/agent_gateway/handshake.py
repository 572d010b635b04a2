"""An agent's first steps: its token, then its hello."""

from __future__ import annotations

import asyncio
import logging

from backend.auth.accounts import Accounts
from backend.auth.credentials import bearer_token
from backend.auth.policy import Principal
from backend.observability.metrics import count_rejected
from backend.realtime.frames import PeerConnection
from protocol.messages import (
    PROTOCOL_VERSION,
    CloseCode,
    Hello,
    ProtocolError,
    agent_to_hub,
)

log = logging.getLogger(__name__)

HELLO_TIMEOUT_S = 10.0


async def authenticate(connection: PeerConnection, accounts: Accounts) -> Principal | None:
    """The agent token the connection carries, or None (the connection is closed, saying why)."""
    token = bearer_token(connection.websocket.headers.get("authorization"))
    principal = None
    if token is not None:
        principal = await asyncio.to_thread(accounts.resolve_token, token)
        if principal is not None and not principal.is_agent:
            principal = None  # a user's token never speaks for a vehicle
    if principal is None:
        reason = (
            "missing agent token (send 'Authorization: Bearer <token>')"
            if token is None
            else "invalid or revoked agent token"
        )
        log.warning("refused agent connection from %s: %s", connection.peer, reason)
        await connection.close(CloseCode.UNAUTHORIZED, reason)
    return principal


async def receive_hello(connection: PeerConnection) -> Hello | None:
    """The first frame, which must be a hello of our protocol within HELLO_TIMEOUT_S; None
    (the connection is closed, saying why) otherwise."""
    try:
        frame = await asyncio.wait_for(connection.receive(), HELLO_TIMEOUT_S)
    except TimeoutError:
        await connection.close(CloseCode.BAD_HELLO, f"no hello within {HELLO_TIMEOUT_S:.0f} s")
        return None
    if frame is None:
        return None
    try:
        message = agent_to_hub.decode(frame)
    except ProtocolError as error:
        count_rejected(connection.surface)
        await connection.close(CloseCode.BAD_HELLO, f"first frame must be a hello: {error.message}")
        return None
    if not isinstance(message, Hello):
        count_rejected(connection.surface)
        await connection.close(
            CloseCode.BAD_HELLO, f"first frame must be a hello, not {message.type}"
        )
        return None
    if message.protocol != PROTOCOL_VERSION:
        count_rejected(connection.surface)
        await connection.close(
            CloseCode.BAD_HELLO,
            f"protocol {message.protocol} is not supported; this hub speaks {PROTOCOL_VERSION}",
        )
        return None
    return message
