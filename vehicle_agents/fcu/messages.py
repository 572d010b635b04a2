"""What the flight controller link's users share: the message type, a link change, a
STATUSTEXT, the wait for the next matching message, and reading and checking frames."""

from __future__ import annotations

import asyncio
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from protocol.mavlink_wire import out_of_range

MavMessage = Any  # pymavlink messages are dynamically generated classes
MessagePredicate = Callable[[MavMessage], bool]


@dataclass(frozen=True)
class LinkChange:
    """The link to the flight controller came up (a heartbeat) or went down, and why."""

    up: bool
    reason: str


@dataclass
class StatusText:
    time: float
    severity: int
    text: str


class FieldOutOfRange(ValueError):
    """A message was not sent: a field's value does not fit its MAVLink wire type."""

    def __init__(self, message_type: str, problems: list[str]) -> None:
        super().__init__(f"{message_type} not sent: {'; '.join(problems)}")


def wire_problems(message: MavMessage) -> list[str]:
    """Each field of a pymavlink message whose value its wire type cannot hold."""
    return out_of_range(
        (name, c_type, getattr(message, name, None))
        for name, c_type in zip(message.fieldnames, message.fieldtypes, strict=True)
    )


async def next_match(queue: asyncio.Queue[MavMessage], within_s: float) -> MavMessage | None:
    """The next message a ``collect`` queue receives, or None after ``within_s`` seconds.

    ``asyncio.timeout``, not ``wait_for``: on Python 3.11 ``wait_for`` can swallow a
    cancellation that lands as the message arrives."""
    try:
        async with asyncio.timeout(within_s):
            return await queue.get()
    except TimeoutError:
        return None


def is_autopilot(heartbeat: MavMessage) -> bool:
    return bool(
        heartbeat.autopilot != mavlink2.MAV_AUTOPILOT_INVALID
        and heartbeat.type != mavlink2.MAV_TYPE_GCS
    )


# One read takes whatever has arrived, up to this: every message in it then costs one
# parse, not a wait, two small reads and a wake-up of the event loop each.
READ_CHUNK = 4096


def read_available(connection: Any, wait_s: float) -> list[MavMessage]:
    """The messages that arrived within ``wait_s``: one select, one read, one parse.

    ``connection.recv`` is pymavlink's, per link type: a TCP read (end of stream raises
    through ``handle_eof``), a UDP datagram (remembering the sender, so replies reach
    it), or what a serial port holds."""
    if not connection.select(wait_s):
        return []
    data = connection.recv(READ_CHUNK)
    if not data:
        return []
    return list(connection.mav.parse_buffer(data) or [])


def raise_closed() -> None:
    raise ConnectionResetError("flight controller closed the connection")
