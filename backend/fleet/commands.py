"""Command dispatch: check a command against the vehicle, send it to its agent, await
the flight controller's answer."""

from __future__ import annotations

import asyncio
import logging
import time
import uuid
from collections.abc import Awaitable, Callable
from dataclasses import dataclass, field

from starlette.websockets import WebSocketDisconnect

from backend.auth.policy import Principal
from backend.errors import CommandTimedOut, InvalidRequest, VehicleOffline
from backend.fleet.registry import FleetRegistry
from backend.observability.metrics import COMMAND_SECONDS
from protocol.messages import (
    Command,
    CommandOutcome,
    CommandRequest,
    Message,
    MissionDownloadCommand,
    MissionUploadCommand,
    ParamListCommand,
    SetModeCommand,
)

log = logging.getLogger(__name__)

SendFrame = Callable[[Message], Awaitable[None]]

# The hub waits this much longer than it lets the agent try, so the agent's own
# timeout report (which names the flight controller) arrives before the hub gives up.
AGENT_REPLY_GRACE_S = 2.0


@dataclass(frozen=True)
class Sender:
    """Who a command comes from, for an agent on another hub: that hub checks the
    principal again and records the command in its name (protocol/routing.py)."""

    principal: Principal
    source: str = "api"
    # What this hub's checks found (safety rails, an override), for that audit row.
    checks: dict[str, object] = field(default_factory=dict)


class AgentChannel:
    """The hub's end of one connected agent, as far as commands are concerned."""

    # True for an agent connected to another hub (backend/realtime/routing.py).
    remote = False

    def __init__(self, send: SendFrame) -> None:
        self._send = send
        self._pending: dict[str, asyncio.Future[CommandOutcome]] = {}

    async def request(
        self, command: Command, timeout_s: float, sender: Sender | None = None
    ) -> CommandOutcome:
        """The agent's answer. ``sender`` matters only to an agent on another hub."""
        request_id = uuid.uuid4().hex
        future: asyncio.Future[CommandOutcome] = asyncio.get_running_loop().create_future()
        self._pending[request_id] = future
        started = time.monotonic()
        outcome = "offline"
        try:
            try:
                await self._send(
                    CommandRequest(request_id=request_id, command=command, timeout_s=timeout_s)
                )
            except (RuntimeError, OSError, WebSocketDisconnect) as error:
                raise VehicleOffline(f"the agent's connection closed: {error}") from None
            result = await asyncio.wait_for(future, timeout_s + AGENT_REPLY_GRACE_S)
            outcome = result.status
            return result
        except TimeoutError:
            outcome = "no_answer"
            raise CommandTimedOut(
                f"{command.name}: the agent did not answer within {timeout_s:.0f} s"
            ) from None
        finally:
            self._pending.pop(request_id, None)
            COMMAND_SECONDS.labels(outcome=outcome).observe(time.monotonic() - started)

    async def send_frame(self, frame: Message) -> None:
        """A frame that expects no answer (manual input)."""
        await self._send(frame)

    def resolve(self, request_id: str, outcome: CommandOutcome) -> bool:
        future = self._pending.get(request_id)
        if future is None or future.done():
            return False
        future.set_result(outcome)
        return True

    def fail_all(self, reason: str) -> None:
        for future in self._pending.values():
            if not future.done():
                future.set_exception(VehicleOffline(reason))


# Exchanges that move a table item by item take longer than one command; over a
# 57600-baud radio an item's round trip can take this long.
PER_ITEM_S = 0.1
LONG_EXCHANGE_S = 60.0


def allowed_time(command: Command, base_s: float) -> float:
    """How long the agent may work on a command before it must answer."""
    match command:
        case MissionUploadCommand(items=items):
            return base_s + PER_ITEM_S * len(items)
        case ParamListCommand() | MissionDownloadCommand():
            return max(base_s, LONG_EXCHANGE_S)
        case _:
            return base_s


class CommandDispatcher:
    def __init__(self, registry: FleetRegistry, timeout_s: float) -> None:
        self._registry = registry
        self._timeout_s = timeout_s

    def detach(self, vehicle_id: str, channel: AgentChannel) -> None:
        """The agent behind `channel` is gone: its unanswered commands fail now."""
        channel.fail_all(f"vehicle {vehicle_id!r} disconnected before answering")

    async def execute(
        self, vehicle_id: str, command: Command, sender: Sender | None = None
    ) -> CommandOutcome:
        record = self._registry.get(vehicle_id)
        if isinstance(command, SetModeCommand) and command.mode not in record.modes:
            raise InvalidRequest(
                "mode",
                f"unknown mode {command.mode!r} for {vehicle_id}; "
                f"it has: {', '.join(record.modes) or 'none reported'}",
            )
        channel = record.channel
        if channel is None:
            raise VehicleOffline(f"vehicle {vehicle_id!r} is not connected")
        outcome = await channel.request(command, allowed_time(command, self._timeout_s), sender)
        log.info("%s %s -> %s", vehicle_id, command.name, outcome.message)
        if outcome.status == "timeout":
            raise CommandTimedOut(outcome.message)
        return outcome
