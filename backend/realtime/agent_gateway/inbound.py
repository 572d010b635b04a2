"""What an agent sends after its hello, each frame to where it goes: telemetry and events
to the store and the live view, scans to the scan service, command results to their caller."""

from __future__ import annotations

import asyncio
import logging
import time

from sqlalchemy.exc import SQLAlchemyError

from backend.fleet.commands import AgentChannel
from backend.manual_control.service import ends_manual_control
from backend.observability.metrics import count_rejected
from backend.realtime.bus import Topic
from backend.realtime.collaborators import GatewayServices
from backend.realtime.frames import PeerConnection
from backend.realtime.sample_refusals import SampleRefusals
from backend.storage.records import LostFrames, StoredEvent, TelemetryEnvelope
from protocol.messages import (
    CommandResult,
    ErrorReply,
    Event,
    Hello,
    LiveState,
    ManualApplied,
    ModeList,
    Pong,
    ProtocolError,
    ScanSourceStats,
    Telemetry,
    Unavailable,
    agent_to_hub,
    state_out_of_range,
)

log = logging.getLogger(__name__)

SCAN_ERROR_INTERVAL_S = 1.0  # refused scans are answered at most this often


class AgentFrames:
    """One agent session's frames after the hello, handled in order."""

    def __init__(
        self, session: PeerConnection, hub: GatewayServices, hello: Hello, channel: AgentChannel
    ) -> None:
        self._session = session
        self.hub = hub
        self._hello = hello
        self._channel = channel
        self._scan_error_at = -SCAN_ERROR_INTERVAL_S
        self._refusals: SampleRefusals | None = None  # made at the first sample

    async def handle(self, frame: str | bytes) -> None:
        hello = self._hello
        channel = self._channel
        if isinstance(frame, bytes):
            await self._ingest_scan(hello, frame)
            return
        try:
            message = agent_to_hub.decode(frame)
        except ProtocolError as error:
            await self._session.reject(error.reply())
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
                if ends_manual_control(message.kind, message.severity):
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
                await self._session.reject(
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
                await self._session.send(
                    ErrorReply(code="invalid_message", message=f"scan: {message}")
                )

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
