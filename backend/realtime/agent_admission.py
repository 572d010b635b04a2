"""One aircraft per vehicle id: who keeps the id when a second agent says hello for it.

A cloned SD card, or a second agent started by mistake, must not take turns with the
first (mixing two flight controllers' states under one id, and sending a command to
whichever is connected at that instant). The first agent keeps the id while it answers;
the newcomer is refused. An agent that reconnects after a network cut, while the hub still
holds its half-dead connection, must get through all the same: the same run (its hello's
``stream_id``) replaces its stale connection at once, and any newcomer takes over a
connection that no longer answers a ping.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

# A WebSocket close reason is at most 123 bytes (RFC 6455, 5.5.1).
MAX_CLOSE_REASON_BYTES = 123


class LiveAgent(Protocol):
    """The connection that holds a vehicle id now."""

    stream_id: str | None
    peer: str

    async def answers_within(self, timeout_s: float) -> bool: ...


@dataclass(frozen=True)
class Takeover:
    """The newcomer gets the id; the old connection is closed with ``reason``."""

    reason: str


@dataclass(frozen=True)
class Clash:
    """The newcomer is refused: ``reason`` for its close frame, ``event`` for the
    operator's event log."""

    reason: str
    event: str


async def judge(
    holder: LiveAgent, vehicle_id: str, stream_id: str, newcomer_peer: str, timeout_s: float
) -> Takeover | Clash:
    """Whether a newcomer saying hello for ``vehicle_id`` as run ``stream_id`` may take
    the id from ``holder``; asks ``holder`` (for up to ``timeout_s``) if it is still there."""
    if holder.stream_id == stream_id:
        return Takeover("replaced by a new connection of the same agent")
    if not await holder.answers_within(timeout_s):
        return Takeover(f"silent for {timeout_s:g} s; another agent took vehicle id over")
    reason = clip_reason(
        f"vehicle id {vehicle_id} clash: another live agent already uses it; "
        "give each aircraft its own --vehicle-id"
    )
    event = (
        f"refused a second agent for vehicle id {vehicle_id} (from {newcomer_peer}, while "
        f"the agent from {holder.peer} is connected and answering): two agents, or two "
        "aircraft, share this id; give each its own --vehicle-id"
    )
    return Clash(reason, event)


def clip_reason(reason: str) -> str:
    """The reason as a close frame can carry it."""
    data = reason.encode()
    if len(data) <= MAX_CLOSE_REASON_BYTES:
        return reason
    return data[: MAX_CLOSE_REASON_BYTES - 3].decode(errors="ignore") + "…"
