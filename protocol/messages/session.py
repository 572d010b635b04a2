"""A connection's own frames, either side: the hub's welcome, its error reply, ping and
pong, and the close codes that end a connection."""

from __future__ import annotations

from enum import IntEnum
from typing import Literal

from pydantic import Field

from protocol.messages.base import PROTOCOL_VERSION, Message, MessageText, VehicleId


class CloseCode(IntEnum):
    """WebSocket close codes the hub uses; 4xxx are application-defined."""

    NORMAL = 1000
    POLICY_VIOLATION = 1008  # repeated malformed frames
    MESSAGE_TOO_BIG = 1009
    BAD_HELLO = 4400  # first frame was not a valid hello, or wrong protocol version
    UNAUTHORIZED = 4401  # missing, wrong, expired or revoked credentials
    FORBIDDEN = 4403  # authenticated, but not allowed (role, vehicle, origin)
    # Two aircraft (a cloned SD card, a second agent started by mistake) must never share
    # one vehicle id, so the agent gives up on 4409 and reconnects on 4410.
    VEHICLE_ID_IN_USE = 4409  # another agent, still answering, holds this vehicle id
    SUPERSEDED = 4410  # replaced by the same agent run reconnecting, or this one fell silent
    TOO_SLOW = 4408  # a client feed that stopped reading for longer than the hub waits


class Welcome(Message):
    type: Literal["welcome"] = "welcome"
    protocol: int = PROTOCOL_VERSION
    vehicle_id: VehicleId


class ErrorReply(Message):
    """Sent to a peer whose frame could not be used; the connection stays open."""

    type: Literal["error"] = "error"
    code: Literal[
        "bad_frame", "invalid_message", "unexpected_message", "too_many_errors", "forbidden"
    ]
    message: MessageText


# The hub pings an agent to learn whether it is still there (another agent wants its
# vehicle id); the agent answers with a pong. Clients ping the hub alike.
class Ping(Message):
    type: Literal["ping"] = "ping"
    nonce: str | None = Field(default=None, max_length=64)


class Pong(Message):
    type: Literal["pong"] = "pong"
    nonce: str | None = Field(default=None, max_length=64)
