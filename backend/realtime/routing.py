"""Commands and stick input for an agent connected to another hub, over NATS.

Each hub answers, for every agent connected to it, three subjects:
``<prefix>.agent.<vehicle>.command`` (request/reply: a command in, the flight
controller's answer out), ``<prefix>.agent.<vehicle>.frame`` (stick frames and a
formation's updates, newest wins, no answer) and ``<prefix>.agent.<vehicle>.here`` (an
empty answer: the vehicle is held here, for hubs that stopped hearing of it). A hub that
has no connection for a vehicle asks the subject; NATS itself finds the hub that serves
it, so there is no directory of who holds what to keep right while hubs come and go. No
hub serving it is NATS's "no responders", at once: the vehicle is offline. An agent that
moves to another hub moves its subjects with it, and after a takeover (hub killed, agent
reconnected elsewhere) only the live hub answers.

On the asking hub, such a vehicle's record (mirrored from the other hub's state on the
bus, ``FleetRegistry.mirror``) has a ``RemoteChannel``: everything that sends to an
agent (commands, leases, the stick relay, formations) reaches it as it reaches a local
one. The hub that asks does the checks (roles, safety rails) against its mirror of the
vehicle, as it would for its own, and sends the command with the user it comes from
(protocol/routing.py). The hub that answers looks that user's token up in the shared
database, checks the permission again, passes the command to the agent, and writes the
audit row and the command log (``carry_out_routed``), within the asker's deadline.

A command without a sender the database knows (a forged message, a client on the bus
that is not a hub) is refused before the agent: counted in
``gcs_rejected_frames_total{surface="bus_command"}`` and logged. NATS's own
authentication (GCS_BUS_USER and GCS_BUS_PASSWORD) keeps such clients off the bus in
the first place; this check holds if it does not.
"""

from __future__ import annotations

import asyncio
import logging
from collections.abc import Awaitable, Callable

from nats.aio.client import Client as Nats
from nats.aio.msg import Msg
from nats.aio.subscription import Subscription
from nats.errors import NoRespondersError
from nats.errors import TimeoutError as NatsTimeout
from pydantic import ValidationError
from starlette.websockets import WebSocketDisconnect

from backend.auth.policy import Principal
from backend.errors import CommandTimedOut, Forbidden, GcsError, VehicleOffline
from backend.fleet.commands import AGENT_REPLY_GRACE_S, AgentChannel, Sender
from backend.fleet.registry import FleetRegistry
from backend.observability.metrics import REJECTED_FRAMES
from protocol.messages import (
    Command,
    CommandOutcome,
    FormationEnd,
    FormationSlot,
    LeaderScan,
    LeaderUpdate,
    ManualFrame,
    Message,
    ProtocolError,
    encode,
    hub_to_agent,
)
from protocol.routing import RoutedAnswer, RoutedCommand, RoutedSender

log = logging.getLogger(__name__)


# The hub-to-agent frames that expect no answer: each crosses to the agent's hub as it is.
ONE_WAY_FRAMES = (ManualFrame, FormationSlot, FormationEnd, LeaderUpdate, LeaderScan)


# The hub's side of a routed command (wired by backend/hub/start.py): who the sender is, per
# the database (None: unknown, revoked, or not as the message says), and carrying the
# command out for them (backend/fleet/command_service.py's carry_out_routed).
SenderCheck = Callable[[RoutedSender], Awaitable[Principal | None]]
Carrier = Callable[[Principal, str, RoutedCommand], Awaitable[CommandOutcome]]


def routed_sender(principal: Principal) -> RoutedSender:
    """The wire form of a command's sender; only a user's token crosses to another hub."""
    if principal.is_agent or principal.token_id is None:
        raise Forbidden(f"{principal.name}: only a user's command crosses to another hub")
    try:
        return RoutedSender(
            name=principal.name,
            role=principal.role,
            token_id=principal.token_id,
            token_kind=principal.token_kind,  # checked by the model
        )
    except ValidationError as error:
        raise Forbidden(f"{principal.name}'s token cannot name them to another hub") from error


def vehicle_token(vehicle_id: str) -> str:
    """A vehicle id as one subject token: '.' separates tokens, and '%' is in no id."""
    return vehicle_id.replace(".", "%2E")


class RemoteChannel(AgentChannel):
    """An agent connected to another hub, as this hub's code sees any agent."""

    remote = True

    def __init__(self, routes: AgentRoutes, vehicle_id: str) -> None:
        super().__init__(self._unsendable)
        self._routes = routes
        self._vehicle_id = vehicle_id

    async def _unsendable(self, message: Message) -> None:
        kind = type(message).__name__
        raise RuntimeError(f"{kind}: {self._vehicle_id} is connected to another hub")

    async def request(
        self, command: Command, timeout_s: float, sender: Sender | None = None
    ) -> CommandOutcome:
        if sender is None:
            # Every routed command names a user, whom the other hub checks and records.
            raise Forbidden(
                f"{command.name}: {self._vehicle_id} is on another hub, which "
                "takes only commands that name their sender"
            )
        return await self._routes.request(self._vehicle_id, command, timeout_s, sender)

    async def send_frame(self, frame: Message) -> None:
        if isinstance(frame, ONE_WAY_FRAMES):
            await self._routes.send_frame(self._vehicle_id, frame)
        else:
            await self._unsendable(frame)


class AgentRoutes:
    """This hub's side of the routing: it serves its own agents' subjects, and asks the
    others' (``RemoteAgents`` of backend/fleet/commands.py)."""

    def __init__(
        self, nats: Nats, prefix: str, registry: FleetRegistry, bus_margin_s: float
    ) -> None:
        self._nats = nats
        self._prefix = prefix
        self._registry = registry
        self._bus_margin_s = bus_margin_s
        self._served: dict[str, list[Subscription]] = {}
        # Commands being answered, each its own task (NATS runs one subscription's
        # callbacks one after the other; a 15 s take-off must not hold up a land).
        self._answering: set[asyncio.Task[None]] = set()
        self.forwarded_frames = 0
        self.refused_commands = 0  # routed commands without a sender the database knows
        self.hub_id = ""  # this hub's id, named in the commands it routes
        self.check_sender: SenderCheck | None = None
        self.carry_out: Carrier | None = None

    def subject(self, vehicle_id: str, kind: str) -> str:
        return f"{self._prefix}.agent.{vehicle_token(vehicle_id)}.{kind}"

    # -- the asking side ---------------------------------------------------------------

    async def request(
        self, vehicle_id: str, command: Command, timeout_s: float, sender: Sender
    ) -> CommandOutcome:
        payload = RoutedCommand(
            command=command,
            timeout_s=timeout_s,
            sender=routed_sender(sender.principal),
            source=sender.source,
            asked_by=self.hub_id,
            checks=sender.checks,
        ).model_dump_json()
        deadline_s = timeout_s + AGENT_REPLY_GRACE_S + self._bus_margin_s
        try:
            reply = await self._nats.request(
                self.subject(vehicle_id, "command"), payload.encode(), timeout=deadline_s
            )
        except NoRespondersError:
            raise VehicleOffline(f"vehicle {vehicle_id!r} is not connected to any hub") from None
        except NatsTimeout:
            raise CommandTimedOut(
                f"{command.name}: the hub holding {vehicle_id} did not answer within "
                f"{deadline_s:.0f} s"
            ) from None
        try:
            answer = RoutedAnswer.model_validate_json(reply.data)
        except ValidationError as error:
            raise VehicleOffline(f"unusable answer from the hub holding {vehicle_id}") from error
        if answer.outcome is not None:
            return answer.outcome
        failure: GcsError
        if answer.error == "timeout":
            failure = CommandTimedOut(answer.message)
        elif answer.error == "refused":
            failure = Forbidden(answer.message)
        else:
            failure = VehicleOffline(answer.message)
        failure.recorded_elsewhere = answer.recorded
        raise failure

    async def send_frame(self, vehicle_id: str, frame: Message) -> None:
        if self._nats.is_connected:
            await self._nats.publish(self.subject(vehicle_id, "frame"), encode(frame).encode())

    # -- the serving side --------------------------------------------------------------

    async def serve(self, vehicle_id: str) -> None:
        """This hub now holds the vehicle's agent: answer for it."""
        await self.withdraw(vehicle_id)
        self._served[vehicle_id] = [
            await self._nats.subscribe(
                self.subject(vehicle_id, "command"), cb=self._command_answerer(vehicle_id)
            ),
            await self._nats.subscribe(
                self.subject(vehicle_id, "frame"), cb=self._frame_forwarder(vehicle_id)
            ),
            await self._nats.subscribe(self.subject(vehicle_id, "here"), cb=self._present),
        ]

    async def is_held(self, vehicle_id: str, timeout_s: float) -> bool:
        """Whether some hub holds the vehicle's agent now (it answers for it)."""
        try:
            await self._nats.request(self.subject(vehicle_id, "here"), b"", timeout=timeout_s)
        except (NoRespondersError, NatsTimeout):
            return False
        return True

    @staticmethod
    async def _present(msg: Msg) -> None:
        await msg.respond(b"")

    async def withdraw(self, vehicle_id: str) -> None:
        """The agent left this hub: another hub (or none) answers for it now."""
        for subscription in self._served.pop(vehicle_id, []):
            try:
                await subscription.unsubscribe()
            except Exception as error:
                # A closed connection has no subscriptions left to end.
                log.debug("unsubscribe %s: %r", vehicle_id, error)

    async def close(self) -> None:
        for task in list(self._answering):
            task.cancel()
        for vehicle_id in list(self._served):
            await self.withdraw(vehicle_id)

    def _command_answerer(self, vehicle_id: str) -> Callable[[Msg], Awaitable[None]]:
        async def answer(msg: Msg) -> None:
            task = asyncio.create_task(self._answer(vehicle_id, msg))
            self._answering.add(task)
            task.add_done_callback(self._answering.discard)

        return answer

    async def _answer(self, vehicle_id: str, msg: Msg) -> None:
        try:
            routed = RoutedCommand.model_validate_json(msg.data)
        except ValidationError as error:
            answer = self._refuse(vehicle_id, f"unusable routed command: {error}")
        else:
            answer = await self._pass_on(vehicle_id, routed)
        try:
            await msg.respond(answer.model_dump_json().encode())
        except Exception as error:
            # The asker gave up or NATS went away: its own deadline answers the operator.
            log.info("answer for %s not sent: %r", vehicle_id, error)

    def _refuse(self, vehicle_id: str, reason: str) -> RoutedAnswer:
        """A command on the subject that names no sender the database knows: nothing
        reaches the agent, and nothing was recorded (the asker, if a hub, records it)."""
        self.refused_commands += 1
        REJECTED_FRAMES.labels(surface="bus_command").inc()
        log.warning("routed command for %s refused: %s", vehicle_id, reason[:300])
        return RoutedAnswer(error="refused", message=f"refused by the hub holding {vehicle_id}")

    async def _pass_on(self, vehicle_id: str, routed: RoutedCommand) -> RoutedAnswer:
        sender = routed.sender
        principal = None
        if self.check_sender is not None and self.carry_out is not None:
            principal = await self.check_sender(sender)
        if principal is None or self.carry_out is None:
            return self._refuse(
                vehicle_id,
                f"{routed.command.name} from {sender.name!r} ({sender.role}, "
                f"{sender.token_kind} token {sender.token_id}, asked by "
                f"{routed.asked_by or 'an unnamed client'}): no such live token and user",
            )
        try:
            outcome = await self.carry_out(principal, vehicle_id, routed)
        except CommandTimedOut as error:
            return RoutedAnswer(error="timeout", message=error.message, recorded=True)
        except Forbidden as error:
            return RoutedAnswer(error="refused", message=error.message, recorded=True)
        except GcsError as error:
            return RoutedAnswer(error="offline", message=error.message, recorded=True)
        log.info(
            "%s %s (for another hub) -> %s (by %s)",
            vehicle_id,
            routed.command.name,
            outcome.message,
            principal.name,
        )
        return RoutedAnswer(outcome=outcome, recorded=True)

    def _frame_forwarder(self, vehicle_id: str) -> Callable[[Msg], Awaitable[None]]:
        async def forward(msg: Msg) -> None:
            try:
                frame = hub_to_agent.decode(msg.data)
                channel = self._registry.get(vehicle_id).channel
            except (ProtocolError, GcsError) as error:
                log.info("frame for %s not forwarded: %s", vehicle_id, error)
                return
            if not isinstance(frame, ONE_WAY_FRAMES):
                log.warning("%s for %s refused: only one-way frames cross", frame.type, vehicle_id)
                return
            if channel is None or channel.remote:
                return  # gone: the agent's deadman holds the vehicle
            try:
                await channel.send_frame(frame)
                self.forwarded_frames += 1
            except (RuntimeError, OSError, WebSocketDisconnect) as error:
                log.info("frame for %s not sent: %s", vehicle_id, error)

        return forward
