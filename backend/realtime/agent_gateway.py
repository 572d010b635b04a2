"""One agent's WebSocket session: authenticate, hello, then telemetry in and commands out."""

from __future__ import annotations

import asyncio
import contextlib
import logging
import time

from sqlalchemy.exc import SQLAlchemyError
from starlette.websockets import WebSocket, WebSocketDisconnect

from backend.auth.credentials import bearer_token
from backend.auth.policy import AGENT_MESSAGE_PERMISSIONS, Principal, authorize_message
from backend.errors import Forbidden, VehicleNotFound
from backend.fleet.commands import AgentChannel
from backend.fleet.registry import FleetRegistry
from backend.observability import metrics
from backend.observability.metrics import Surface, count_rejected
from backend.realtime.agent_admission import Clash, judge
from backend.realtime.bus import Topic
from backend.realtime.collaborators import GatewayServices
from backend.realtime.frames import FrameTooLarge, PeerConnection
from backend.realtime.sample_refusals import SampleRefusals
from backend.storage.records import LostFrames, StoredEvent, TelemetryEnvelope
from backend.storage.sequences import Gap, StreamKey
from protocol.messages import (
    PROTOCOL_VERSION,
    Ack,
    CloseCode,
    CommandResult,
    ErrorReply,
    Event,
    Hello,
    LiveState,
    ManualApplied,
    ModeList,
    Ping,
    Pong,
    ProtocolError,
    Resend,
    ScanSourceStats,
    SequencedKind,
    Telemetry,
    Unavailable,
    Welcome,
    agent_to_hub,
    state_out_of_range,
)

log = logging.getLogger(__name__)

HELLO_TIMEOUT_S = 10.0
SCAN_ERROR_INTERVAL_S = 1.0  # refused scans are answered at most this often
ACK_INTERVAL_S = 0.5  # an agent is told what is stored at most this often


# An agent's "manual" event at WARNING or worse: browser control has ended on the vehicle.
MANUAL_ENDED_SEVERITY = 4


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
        # Acks (the newest per stream wins) and resend requests from the storage writer,
        # sent by this session's own task so the writer never waits on a socket.
        self._acks: dict[str, dict[str, int]] = {}
        self._resends: list[Resend] = []
        self._news = asyncio.Event()
        self._scan_error_at = -SCAN_ERROR_INTERVAL_S
        self._refusals: SampleRefusals | None = None  # made at the first sample

    def acknowledge(self, key: StreamKey, seq: int) -> None:
        if seq >= 0:
            self._acks.setdefault(key.stream_id, {})[key.kind] = seq
            self._news.set()

    def request_resend(self, gap: Gap) -> None:
        log.info(
            "asking %s for %s %d-%d of stream %s",
            gap.key.vehicle_id,
            gap.key.kind,
            gap.first_seq,
            gap.last_seq,
            gap.key.stream_id,
        )
        self._resends.append(
            Resend(
                stream_id=gap.key.stream_id,
                kind=gap.key.kind,
                first_seq=gap.first_seq,
                last_seq=gap.last_seq,
            )
        )
        self._news.set()

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

    async def _send_sequence_news(self) -> None:
        while True:
            await self._news.wait()
            self._news.clear()
            acks, self._acks = self._acks, {}
            resends, self._resends = self._resends, []
            for stream_id, by_kind in acks.items():
                await self.send(
                    Ack(
                        stream_id=stream_id,
                        telemetry_seq=by_kind.get("telemetry"),
                        event_seq=by_kind.get("event"),
                    )
                )
            for resend in resends:
                await self.send(resend)
            # Pacing: acks arriving meanwhile fold into one per stream. Without it a fleet
            # larger than the writer's batch gets an ack for nearly every frame it sends,
            # as many frames out as in; the agent keeps its frames until acked either way.
            await asyncio.sleep(ACK_INTERVAL_S)

    async def serve(self) -> None:
        await self.websocket.accept()
        principal = await self._authenticate()
        if principal is None:
            return
        self.token_id = principal.token_id
        try:
            hello = await self._receive_hello()
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

    async def _authenticate(self) -> Principal | None:
        token = bearer_token(self.websocket.headers.get("authorization"))
        principal = None
        if token is not None:
            principal = await asyncio.to_thread(self.hub.accounts.resolve_token, token)
            if principal is not None and not principal.is_agent:
                principal = None  # a user's token never speaks for a vehicle
        if principal is None:
            reason = (
                "missing agent token (send 'Authorization: Bearer <token>')"
                if token is None
                else "invalid or revoked agent token"
            )
            log.warning("refused agent connection from %s: %s", self.peer, reason)
            await self.close(CloseCode.UNAUTHORIZED, reason)
        return principal

    async def _receive_hello(self) -> Hello | None:
        try:
            frame = await asyncio.wait_for(self.receive(), HELLO_TIMEOUT_S)
        except TimeoutError:
            await self.close(CloseCode.BAD_HELLO, f"no hello within {HELLO_TIMEOUT_S:.0f} s")
            return None
        if frame is None:
            return None
        try:
            message = agent_to_hub.decode(frame)
        except ProtocolError as error:
            count_rejected(self.surface)
            await self.close(CloseCode.BAD_HELLO, f"first frame must be a hello: {error.message}")
            return None
        if not isinstance(message, Hello):
            count_rejected(self.surface)
            await self.close(
                CloseCode.BAD_HELLO, f"first frame must be a hello, not {message.type}"
            )
            return None
        if message.protocol != PROTOCOL_VERSION:
            count_rejected(self.surface)
            await self.close(
                CloseCode.BAD_HELLO,
                f"protocol {message.protocol} is not supported; this hub speaks {PROTOCOL_VERSION}",
            )
            return None
        return message

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
            restart = _restart_gap(hub.registry, hello, time.time())
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
            news = asyncio.create_task(self._send_sequence_news())
            await self._ask_for_open_gaps(vehicle_id)
            try:
                # An empty frame is a frame (refused as such), not the end of the session.
                while (frame := await self.receive()) is not None:
                    self._frame_arrived.set()
                    self._handling = True
                    try:
                        await self._handle_frame(hello, channel, frame)
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

    async def _handle_frame(self, hello: Hello, channel: AgentChannel, frame: str | bytes) -> None:
        if isinstance(frame, bytes):
            await self._ingest_scan(hello, frame)
            return
        try:
            message = agent_to_hub.decode(frame)
        except ProtocolError as error:
            await self.reject(error.reply())
            return
        match message:
            case Telemetry():
                await self._ingest(hello, message)
            case LiveState(time=at, state=state):
                if problems := state_out_of_range(state):
                    # for the live view only, never stored: dropped and counted
                    self._sample_refusals(hello).count(problems, "a live state")
                    return
                if self.hub.registry.apply_live(hello.vehicle_id, at, state):
                    await self.hub.publish_state(self.hub.registry.get(hello.vehicle_id))
            case Event():
                stored = StoredEvent(
                    hello.vehicle_id,
                    message.stream_id or hello.stream_id,
                    message.seq,
                    message.time,
                    message.kind,
                    message.severity,
                    message.text,
                    message.mission_item,
                    message.photo,
                )
                await self.hub.bus.publish(Topic.STORAGE, hello.vehicle_id, stored)
                await self.hub.publish_event(stored)
                if message.kind == "manual" and (message.severity or 7) <= MANUAL_ENDED_SEVERITY:
                    await self._end_manual_control(hello.vehicle_id, message.text)
            case Unavailable():
                log.warning(
                    "%s no longer has %s %d-%d: %s",
                    hello.vehicle_id,
                    message.kind,
                    message.first_seq,
                    message.last_seq,
                    message.reason,
                )
                lost = LostFrames(
                    hello.vehicle_id,
                    message.stream_id,
                    message.kind,
                    message.first_seq,
                    message.last_seq,
                    message.reason,
                )
                await self.hub.bus.publish(Topic.STORAGE, hello.vehicle_id, lost)
            case CommandResult(request_id=request_id, outcome=outcome):
                if not channel.resolve(request_id, outcome):
                    log.info(
                        "late or unknown command result %s from %s", request_id, hello.vehicle_id
                    )
            case Pong():
                pass  # its arrival answered answers_within()
            case ManualApplied(seq=seq, sent_ms=sent_ms):
                await self.hub.manual_control.echo(hello.vehicle_id, seq, sent_ms)
            case ScanSourceStats(source=source, counts=counts):
                self.hub.scans.source_reported(hello.vehicle_id, source, dict(counts))
            case ModeList(modes=modes):
                await self._take_modes(hello, modes)
            case Hello():
                await self.reject(
                    ErrorReply(code="unexpected_message", message="hello was already received")
                )

    async def _take_modes(self, hello: Hello, modes: list[str]) -> None:
        """The autopilot's own mode list replaces the agent's fixed table: in the live
        state (the dashboard's picker, set_mode's check) and in the store (the list an
        offline vehicle shows after a restart)."""
        hub = self.hub
        record = hub.registry.set_modes(hello.vehicle_id, modes)
        log.info("%s lists its modes: %s", hello.vehicle_id, ", ".join(modes))
        try:
            await asyncio.to_thread(hub.repository.set_modes, hello.vehicle_id, modes)
        except SQLAlchemyError as error:
            log.warning("could not store the modes of %s (%s)", hello.vehicle_id, error)
        await hub.publish_state(record)

    async def _end_manual_control(self, vehicle_id: str, why: str) -> None:
        """The agent ended browser control (deadman hold, the RC pilot's mode change)."""
        await self.hub.manual_control.end_on_vehicle(vehicle_id, why)

    async def _ingest_scan(self, hello: Hello, data: bytes) -> None:
        """A binary frame is a LIDAR scan. A refused one is counted in the vehicle's scan
        diagnostics and answered (at most once a second), never the end of the link: a
        sensor's bad turn must not cost the vehicle its telemetry."""
        try:
            await self.hub.scans.ingest(hello.vehicle_id, hello.stream_id, data)
        except ValueError as refusal:
            count_rejected("agent_scan")
            message = getattr(refusal, "message", str(refusal))
            now = time.monotonic()
            if now - self._scan_error_at >= SCAN_ERROR_INTERVAL_S:
                self._scan_error_at = now
                log.info("scan from %s refused: %s", hello.vehicle_id, message)
                await self.send(ErrorReply(code="invalid_message", message=f"scan: {message}"))

    def _sample_refusals(self, hello: Hello) -> SampleRefusals:
        if self._refusals is None:
            self._refusals = SampleRefusals(hello.vehicle_id)
        return self._refusals

    async def _ingest(self, hello: Hello, telemetry: Telemetry) -> None:
        hub = self.hub
        stream_id = telemetry.stream_id or hello.stream_id
        refusals = self._sample_refusals(hello)
        if problems := state_out_of_range(telemetry.state):
            # An impossible value (latitude 91, altitude 1e308): the sample is neither
            # stored nor shown, the link goes on. Its number is recorded as refused.
            if (run := refusals.refuse(stream_id, telemetry.seq, problems)) is not None:
                await hub.bus.publish(Topic.STORAGE, hello.vehicle_id, run)
            return
        if (run := refusals.flush()) is not None:
            # before this sample, so that the store never takes the refused ones for a hole
            await hub.bus.publish(Topic.STORAGE, hello.vehicle_id, run)
        envelope = TelemetryEnvelope(hello.vehicle_id, stream_id, telemetry)
        # Storage is reliable: if the writer is behind, this waits, and so does the agent.
        # Replays go there too; the writer knows what it has stored.
        await hub.bus.publish(Topic.STORAGE, hello.vehicle_id, envelope)
        if stream_id == hello.stream_id and hub.registry.apply(
            hello.vehicle_id, stream_id, telemetry
        ):
            record = hub.registry.get(hello.vehicle_id)
            # The live rate on /metrics: new samples only, not a backlog replayed or resent.
            record.count_frame(time.monotonic())
            await hub.publish_state(record)


def _restart_gap(registry: FleetRegistry, hello: Hello, now: float) -> str | None:
    """What an agent that comes back as a new run (it restarted) left unrecorded: nothing
    was sampled between its earlier run's last sample the hub saw and this hello, and
    what that run had not yet had acknowledged, it kept only in memory. None when the
    same run reconnects (its outbox replays what is missing) or the hub knows no earlier
    run (it restarted too)."""
    try:
        record = registry.get(hello.vehicle_id)
    except VehicleNotFound:
        return None
    earlier = record.earlier_run(hello.stream_id)
    if earlier is None:
        return None
    run, last_seq = earlier
    since = "" if record.last_seen is None else f" ({now - record.last_seen:.1f} s ago)"
    return (
        f"agent restarted: run {run} ended with sample {last_seq}{since}; no telemetry "
        f"between it and run {hello.stream_id}, which starts now"
    )
