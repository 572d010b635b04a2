"""One agent's WebSocket session: authenticate, hello, then telemetry in and commands out."""

from __future__ import annotations

import asyncio
import contextlib
import logging
import time

from sqlalchemy.exc import SQLAlchemyError
from starlette.websockets import WebSocket, WebSocketDisconnect

from backend.auth.policy import AGENT_MESSAGE_PERMISSIONS, authorize_message
from backend.errors import Forbidden
from backend.fleet.commands import AgentChannel
from backend.observability import metrics
from backend.observability.metrics import Surface
from backend.realtime.agent_admission import Clash, judge
from backend.realtime.agent_gateway.handshake import authenticate, receive_hello
from backend.realtime.agent_gateway.inbound import AgentFrames
from backend.realtime.agent_gateway.restarts import restart_gap
from backend.realtime.agent_gateway.sequence_news import SequenceNews
from backend.realtime.collaborators import GatewayServices
from backend.realtime.frames import FrameTooLarge, PeerConnection
from backend.storage.sequences import Gap, StreamKey
from protocol.messages import (
    CloseCode,
    Hello,
    Ping,
    SequencedKind,
    Welcome,
)

log = logging.getLogger(__name__)


class AgentSession(PeerConnection):
    surface: Surface = "agent_ws"

    def __init__(self, websocket: WebSocket, hub: GatewayServices) -> None:
        super().__init__(websocket, hub.settings.max_frame_bytes, hub.settings.max_bad_frames)
        self.hub = hub
        self.token_id: int | None = None
        self.stream_id: str | None = None  # the agent run's, from its hello
        # For the liveness check when another agent wants this vehicle id.
        self._frame_arrived = asyncio.Event()
        self._handling = False
        self._news = SequenceNews()  # acks and resend requests, sent by serve()'s own task

    def acknowledge(self, key: StreamKey, seq: int) -> None:
        self._news.acknowledge(key, seq)

    def request_resend(self, gap: Gap) -> None:
        self._news.request_resend(gap)

    async def answers_within(self, timeout_s: float) -> bool:
        """Whether the agent is still there: it sends a frame (the pong to this ping, or
        anything else) within ``timeout_s``. A session busy storing a frame it received
        (the writer is behind) is busy, not gone."""
        loop = asyncio.get_running_loop()
        deadline = loop.time() + timeout_s
        self._frame_arrived.clear()
        try:
            await asyncio.wait_for(self.send(Ping(nonce="are-you-there")), timeout_s)
        except Exception as error:
            # Any failure to send (closed, reset, stuck) is the answer: it cannot be reached.
            log.info("agent at %s cannot be pinged: %r", self.peer, error)
            return False
        try:
            await asyncio.wait_for(self._frame_arrived.wait(), max(0.0, deadline - loop.time()))
        except TimeoutError:
            return self._handling
        return True

    async def serve(self) -> None:
        await self.websocket.accept()
        principal = await authenticate(self, self.hub.accounts)
        if principal is None:
            return
        self.token_id = principal.token_id
        try:
            hello = await receive_hello(self)
            if hello is None:
                return
            try:
                authorize_message(principal, "hello", AGENT_MESSAGE_PERMISSIONS, hello.vehicle_id)
            except Forbidden as refusal:
                log.warning("refused agent from %s: %s", self.peer, refusal.message)
                await self.close(CloseCode.FORBIDDEN, refusal.message)
                return
            connected = metrics.CONNECTIONS.labels(kind="agent")
            connected.inc()
            try:
                await self._serve_vehicle(hello)
            finally:
                connected.dec()
        except FrameTooLarge as error:
            log.warning("closing agent %s: %s", self.peer, error)
            await self.close(CloseCode.MESSAGE_TOO_BIG, str(error))
        except WebSocketDisconnect:
            pass

    async def _ask_for_open_gaps(self, vehicle_id: str) -> None:
        """Gaps stored as still open (perhaps by a hub that died since) are asked for at
        once: an agent with nothing more to send on that stream must still answer, so
        that a loss is recorded as one."""
        try:
            rows = await asyncio.to_thread(self.hub.repository.open_gaps_of, vehicle_id)
        except SQLAlchemyError as error:
            # The database is away: the session goes on (its operators may need to land
            # the vehicle). Gaps this hub saw open itself are asked for as they are found;
            # those stored by an earlier run wait for the agent's next connection.
            log.warning("could not read %s's open gaps (%s); serving it", vehicle_id, error)
            return
        kinds: dict[str, SequencedKind] = {"telemetry": "telemetry", "event": "event"}
        for stream_id, kind, first, last in rows:
            if kind in kinds:
                key = StreamKey(vehicle_id, stream_id, kinds[kind])
                self.request_resend(Gap(key, first, last))

    async def _serve_vehicle(self, hello: Hello) -> None:
        hub = self.hub
        vehicle_id = hello.vehicle_id
        # One admission at a time per vehicle id, so that two newcomers cannot both take
        # over; the first agent keeps the id while it answers (see agent_admission).
        async with hub.agent_admissions.setdefault(vehicle_id, asyncio.Lock()):
            previous = hub.agent_sessions.get(vehicle_id)
            verdict = None
            if previous is not None:
                verdict = await judge(
                    previous,
                    vehicle_id,
                    hello.stream_id,
                    self.peer,
                    hub.settings.agent_liveness_timeout_s,
                )
            if isinstance(verdict, Clash):
                # Before the store or the registry hear of this hello: the vehicle stays
                # the first agent's, its state and commands included.
                log.error("vehicle id clash: %s", verdict.event)
                await hub.store_event(vehicle_id, "id_clash", verdict.event, severity=3)
                await self.close(CloseCode.VEHICLE_ID_IN_USE, verdict.reason)
                return
            try:
                await asyncio.to_thread(hub.repository.upsert_vehicle, hello, time.time())
            except SQLAlchemyError as error:
                # A vehicle the store already has may reconnect during a database outage
                # (its operators may need to land it); its row is refreshed at the next
                # connection. A new one needs its row first: its telemetry is stored
                # against it.
                if vehicle_id not in {record.id for record in hub.registry.all()}:
                    raise
                log.warning("could not refresh %s in the store (%s); serving it", vehicle_id, error)
            self.stream_id = hello.stream_id
            restart = restart_gap(hub.registry, hello, time.time())
            channel = AgentChannel(self.send)
            record = hub.registry.connect(hello, channel)
            # Ours before the old one closes, so that its ending leaves the vehicle online.
            hub.agent_sessions[vehicle_id] = self
            if hub.routes is not None:
                await hub.routes.serve(vehicle_id)
        if previous is not None and verdict is not None:
            log.warning(
                "agent %s: its old connection %s: %s", vehicle_id, previous.peer, verdict.reason
            )
            try:
                await previous.close(CloseCode.SUPERSEDED, verdict.reason)
            except Exception as error:
                # The old peer's failure, not this session's: it is gone either way.
                log.info("old connection of %s already gone: %r", vehicle_id, error)
        log.info(
            "agent %s connected from %s (%s %s)",
            vehicle_id,
            self.peer,
            hello.autopilot,
            hello.vehicle_type,
        )
        try:
            await self.send(Welcome(vehicle_id=vehicle_id))
            await hub.store_event(vehicle_id, "link_up", f"agent connected from {self.peer}")
            if restart is not None:
                await hub.store_event(vehicle_id, "agent_restart", restart, severity=4)
            await hub.publish_state(record)
            # Not a TaskGroup: the receive loop's own exceptions (disconnect, oversized
            # frame) must reach serve() as they are, not wrapped in a group.
            news = asyncio.create_task(self._news.run(self.send))
            frames = AgentFrames(self, hub, hello, channel)
            await self._ask_for_open_gaps(vehicle_id)
            try:
                # An empty frame is a frame (refused as such), not the end of the session.
                while (frame := await self.receive()) is not None:
                    self._frame_arrived.set()
                    self._handling = True
                    try:
                        await frames.handle(frame)
                    finally:
                        self._handling = False
            finally:
                news.cancel()
                # The session is over; a send that failed on its way out changes nothing.
                with contextlib.suppress(asyncio.CancelledError, Exception):
                    await news
        finally:
            hub.dispatcher.detach(vehicle_id, channel)
            # A superseded session leaves the vehicle to its successor, still online.
            if hub.agent_sessions.get(vehicle_id) is self:
                del hub.agent_sessions[vehicle_id]
                if hub.routes is not None:
                    await hub.routes.withdraw(vehicle_id)
            if (offline := hub.registry.disconnect(vehicle_id, channel)) is not None:
                await hub.publish_state(offline)
                await hub.store_event(vehicle_id, "link_down", "agent disconnected")
            log.info("agent %s disconnected", vehicle_id)
