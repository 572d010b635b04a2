"""The authenticated WebSocket link to the hub, reconnecting with backoff."""

from __future__ import annotations

import asyncio
import logging
import time
from collections.abc import Awaitable, Callable, Sequence
from dataclasses import dataclass
from typing import Any

from pydantic import TypeAdapter, ValidationError
from websockets.asyncio.client import ClientConnection, connect
from websockets.exceptions import ConnectionClosed, InvalidHandshake

from common.retry import Backoff, Retries, Sleep
from protocol.messages import (
    MAX_FRAME_BYTES,
    Ack,
    CloseCode,
    Command,
    CommandOutcome,
    CommandRequest,
    CommandResult,
    ErrorReply,
    FormationEnd,
    FormationSlot,
    Hello,
    LeaderScan,
    LeaderUpdate,
    LiveState,
    ManualApplied,
    ManualFrame,
    ModeList,
    Ping,
    Pong,
    ProtocolError,
    RequestId,
    Resend,
    ScanSourceStats,
    VehicleState,
    Welcome,
    encode,
    hub_to_agent,
)
from vehicle_agents.hub.outbox import Outbox
from vehicle_agents.sensors.relay import ScanOutbox

log = logging.getLogger(__name__)

CommandHandler = Callable[[Command], Awaitable[CommandOutcome]]


@dataclass(frozen=True)
class HubTimeouts:
    welcome_s: float = 5.0
    reconnect: Backoff = Backoff(initial_s=0.5, max_s=10.0)
    # A refused token will not fix itself quickly; retry slowly instead of hammering
    # (on average 7.5 s, then 15 s, then 30 s from the third refusal in a row).
    unauthorized: Backoff = Backoff(initial_s=15.0, max_s=60.0)
    ping_interval_s: float = 5.0
    live_state_interval_s: float = 0.5
    scan_stats_interval_s: float = 5.0


COMMAND_ANSWER_MARGIN_S = 0.5
# More frames than this waiting to be sent (a second or two of telemetry) is a backlog.
BEHIND_FRAMES = 20


class HubRefused(Exception):
    """The hub answered the hello with something other than a welcome."""


class VehicleIdInUse(Exception):
    """The hub refused this agent: another agent, still connected, holds its vehicle id.
    Retrying would not help (the hub keeps the first agent); a person must give one of
    the two aircraft its own id."""


class HubClosed(Exception):
    """The hub link ended; ``code`` is the WebSocket close code, if one was received."""

    def __init__(self, code: int | None, reason: str) -> None:
        super().__init__(f"closed with code {code}: {reason}")
        self.code = code
        self.reason = reason


class ModeReport:
    """The mode names the hub should list for the vehicle: each hello carries the current
    ones, and a change while connected (the autopilot listed its own) goes as a ModeList."""

    def __init__(self, names: list[str]) -> None:
        self.names = list(names)
        self.changed = asyncio.Event()

    def update(self, names: list[str]) -> None:
        if names != self.names:
            self.names = list(names)
            self.changed.set()


class HubLink:
    def __init__(
        self,
        url: str,
        token: str,
        hello: Hello,
        outbox: Outbox,
        on_command: CommandHandler,
        timeouts: HubTimeouts | None = None,
        live_state: Callable[[], VehicleState] | None = None,
        on_manual: Callable[[ManualFrame], ManualApplied | None] | None = None,
        scans: ScanOutbox | None = None,
        scan_stats: Callable[[], ScanSourceStats | None] | None = None,
        on_formation: Callable[[FormationSlot | FormationEnd | LeaderUpdate | LeaderScan], None]
        | None = None,
        fallback_urls: Sequence[str] = (),
        modes: ModeReport | None = None,
        reconnect_sleep: Sleep = asyncio.sleep,
    ) -> None:
        # Several hubs (docs/deployer.md "Several hubs"): after a failed or ended session the next
        # attempt goes to the next URL, round the list, still after a jittered wait, so
        # the agents of a hub that died spread over the others.
        self.urls = [url, *fallback_urls]
        self.url = url
        self._token = token
        self._hello = hello
        self._outbox = outbox
        self._on_command = on_command
        self.timeouts = timeouts or HubTimeouts()
        self._live_state = live_state
        self._on_manual = on_manual
        self._on_formation = on_formation
        self._scans = scans
        self._scan_stats = scan_stats
        self._modes = modes
        self.connected = asyncio.Event()
        self.disconnected = asyncio.Event()
        self.disconnected.set()
        self._ever_welcomed = False
        # The agent's paced clock: the reconnect waits are capped to fit the hub-link
        # failsafe's timeout, which is counted on it (vehicle_agents/control/hub_failsafe.py).
        self._reconnect_sleep = reconnect_sleep

    async def run(self) -> None:
        # Jittered, so a fleet that lost its hub does not knock again all at once.
        unreachable = Retries(self.timeouts.reconnect, self._reconnect_sleep)
        refused = Retries(self.timeouts.unauthorized)
        attempt = 0
        while True:
            self.url = self.urls[attempt % len(self.urls)]
            attempt += 1
            retries = unreachable
            try:
                await self._session()
            except* HubClosed as group:
                closed = group.exceptions[0]
                assert isinstance(closed, HubClosed)
                if closed.code == CloseCode.VEHICLE_ID_IN_USE:
                    raise VehicleIdInUse(
                        f"the hub refused vehicle id {self._hello.vehicle_id!r}: "
                        f"{closed.reason}. Another agent that uses this id is connected "
                        "(a second agent on this computer, or a cloned SD card on another "
                        "aircraft). Give each aircraft its own vehicle id (--vehicle-id, "
                        "GCS_AGENT_VEHICLE_ID or vehicle_id in the config file); this agent "
                        "stops rather than take turns with the other one."
                    ) from None
                if closed.code == CloseCode.UNAUTHORIZED:
                    log.error("hub refused this agent's token: %s", closed.reason)
                    retries = refused
                else:
                    log.warning("hub closed the link (%s %s)", closed.code, closed.reason)
            except* ConnectionClosed as group:
                # The link dropped while sending (outbox or a command's answer).
                log.warning("hub link lost: %s", group.exceptions[0])
            except* (OSError, InvalidHandshake, TimeoutError, HubRefused) as group:
                log.warning("hub %s unreachable: %s", self.url, group.exceptions[0])
            finally:
                self.connected.clear()
                self.disconnected.set()
            if self._ever_welcomed:
                unreachable.reset()
                refused.reset()
                self._ever_welcomed = False
            await retries.wait()

    async def _session(self) -> None:
        async with connect(
            self.url,
            additional_headers={"Authorization": f"Bearer {self._token}"},
            max_size=MAX_FRAME_BYTES,
            # No permessage-deflate on the agent link: its frames are small and many, and
            # compressing them cost the hub more CPU than the link saves (docs/reference.md, Scale).
            compression=None,
            ping_interval=self.timeouts.ping_interval_s,
            open_timeout=self.timeouts.welcome_s,
        ) as websocket:
            hello = self._hello
            if self._modes is not None:
                self._modes.changed.clear()  # this hello carries the names as they are now
                hello = hello.model_copy(update={"modes": self._modes.names})
            try:
                await websocket.send(encode(hello))
                reply = await asyncio.wait_for(websocket.recv(), self.timeouts.welcome_s)
            except ConnectionClosed:
                raise HubClosed(websocket.close_code, websocket.close_reason or "") from None
            welcome = hub_to_agent.decode(reply)
            if not isinstance(welcome, Welcome):
                raise HubRefused(f"expected welcome, got {welcome.type}")
            log.info(
                "connected to hub as %s (%d frames to deliver)",
                welcome.vehicle_id,
                len(self._outbox),
            )
            self.connected.set()
            self.disconnected.clear()
            self._ever_welcomed = True
            self._outbox.link_up()
            if self._live_state is not None and self._outbox.backlog() > BEHIND_FRAMES:
                # Ahead of the backlog, so the hub's live view never shows the past.
                await websocket.send(encode(self._live_now()))
            try:
                async with asyncio.TaskGroup() as tasks:
                    tasks.create_task(self._send_outbox(websocket))
                    if self._scans is not None:
                        tasks.create_task(self._send_scans(websocket, self._scans))
                    if self._live_state is not None:
                        tasks.create_task(self._send_live_while_behind(websocket))
                    if self._scan_stats is not None:
                        tasks.create_task(self._send_scan_stats(websocket, self._scan_stats))
                    if self._modes is not None:
                        tasks.create_task(self._send_mode_changes(websocket, self._modes))
                    try:
                        async for frame in websocket:
                            self._handle_frame(frame, websocket, tasks)
                    except ConnectionClosed:
                        pass
                    raise HubClosed(websocket.close_code, websocket.close_reason or "")
            finally:
                # Whatever was sent and not acknowledged goes again on the next link.
                self._outbox.link_down()

    async def _send_live_while_behind(self, websocket: ClientConnection) -> None:
        """While a backlog replays, the hub's live view gets the vehicle as it is now,
        so the map does not re-fly the outage."""
        while True:
            await asyncio.sleep(self.timeouts.live_state_interval_s)
            if self._outbox.backlog() > BEHIND_FRAMES:
                await websocket.send(encode(self._live_now()))

    async def _send_scan_stats(
        self, websocket: ClientConnection, stats: Callable[[], ScanSourceStats | None]
    ) -> None:
        """The LIDAR parser's counts for the hub's scan diagnostics: at the start of each
        session, then whenever they changed, checked every few seconds."""
        sent: ScanSourceStats | None = None
        while True:
            current = stats()
            if current is not None and current != sent:
                await websocket.send(encode(current))
                sent = current
            await asyncio.sleep(self.timeouts.scan_stats_interval_s)

    async def _send_mode_changes(self, websocket: ClientConnection, modes: ModeReport) -> None:
        while True:
            await modes.changed.wait()
            modes.changed.clear()
            await websocket.send(encode(ModeList(modes=modes.names)))

    def _live_now(self) -> LiveState:
        assert self._live_state is not None
        return LiveState(time=time.time(), state=self._live_state())

    async def _send_outbox(self, websocket: ClientConnection) -> None:
        while True:
            await websocket.send(await self._outbox.next_frame())

    async def _send_scans(self, websocket: ClientConnection, scans: ScanOutbox) -> None:
        """Binary scan frames, newest first: their own queue, so they never wait behind
        telemetry nor push it out."""
        while True:
            frame = await scans.next_frame()
            try:
                await websocket.send(frame)
            except ConnectionClosed:
                scans.unsent(frame)
                raise
            scans.sent += 1

    def _handle_frame(
        self, frame: str | bytes, websocket: ClientConnection, tasks: asyncio.TaskGroup
    ) -> None:
        try:
            message = hub_to_agent.decode(frame)
        except ProtocolError as error:
            log.warning("unusable frame from hub: %s", error.message)
            request_id = _command_request_id(error.parsed)
            if request_id is not None:
                # The hub is waiting for this answer; nothing reached the vehicle.
                outcome = CommandOutcome(
                    status="failed", message=f"command refused by the agent: {error.message}"
                )
                result = CommandResult(request_id=request_id, outcome=outcome)
                tasks.create_task(websocket.send(encode(result)))
            return
        except (RecursionError, ValueError) as error:
            # What the JSON parser itself chokes on (30,000 '[', a 5,000-digit number):
            # unusable like any other frame, never the end of the agent.
            log.warning("unusable frame from hub: %s", type(error).__name__)
            return
        match message:
            case Ack():
                self._outbox.acknowledge(message)
            case Resend():
                for answer in self._outbox.resend(message):
                    log.warning(
                        "hub asked for %s %d-%d, which the outbox dropped",
                        answer.kind,
                        answer.first_seq,
                        answer.last_seq,
                    )
                    tasks.create_task(websocket.send(encode(answer)))
            case CommandRequest():
                tasks.create_task(self._run_command(message, websocket))
            case ErrorReply(code=code, message=text):
                log.warning("hub reported %s: %s", code, text)
            case Ping(nonce=nonce):
                # The hub asks whether this agent is still there (another agent wants
                # its vehicle id): answered at once, ahead of the outbox.
                tasks.create_task(websocket.send(encode(Pong(nonce=nonce))))
            case ManualFrame():
                # Handled at once, never queued: the newest stick position is the one flown.
                if self._on_manual is not None:
                    try:
                        applied = self._on_manual(message)
                    except Exception:
                        # A frame that cannot be flown (the flight controller's link went
                        # down under it) is lost, like any late stick input; raised here
                        # it would end the hub session, and the link would flap at the
                        # pilot's 25 Hz while the flight controller is away.
                        log.exception("stick input %d not flown", message.seq)
                        applied = None
                    if applied is not None:
                        tasks.create_task(websocket.send(encode(applied)))
            case FormationSlot() | FormationEnd() | LeaderUpdate() | LeaderScan():
                # at once, like stick frames: the newest leader state is the one flown
                if self._on_formation is not None:
                    self._on_formation(message)
            case Welcome():
                log.warning("unexpected second welcome from hub")

    async def _run_command(self, request: CommandRequest, websocket: ClientConnection) -> None:
        log.info("command %s: %s", request.request_id, request.command.name)
        # Within the hub's deadline, with room for the answer to travel: once the hub has
        # told the operator "timeout", no later step (arming, then take-off) may follow.
        allowed_s = max(0.5, request.timeout_s - COMMAND_ANSWER_MARGIN_S)
        try:
            async with asyncio.timeout(allowed_s):
                outcome = await self._on_command(request.command)
        except TimeoutError:
            outcome = CommandOutcome(
                status="timeout",
                message=f"{request.command.name}: not finished within {allowed_s:.1f} s; "
                "the agent stopped it there",
            )
        except Exception as error:
            # An error escaping here would end the session's TaskGroup, and with it the
            # agent: the command fails, the link and the vehicle's failsafe go on.
            log.exception("command %s failed inside the agent", request.request_id)
            outcome = CommandOutcome(
                status="failed", message=f"{request.command.name}: agent error: {error}"
            )
        log.info("command %s: %s", request.request_id, outcome.message)
        await websocket.send(encode(CommandResult(request_id=request.request_id, outcome=outcome)))


_request_id: TypeAdapter[str] = TypeAdapter(RequestId)


def _command_request_id(parsed: dict[str, Any] | None) -> str | None:
    """The request_id of a command frame that failed validation (the decoder's parse of
    it), so that it can still be answered; None for anything else, or for an id that
    could not be echoed back."""
    if parsed is None or parsed.get("type") != "command":
        return None
    try:
        return _request_id.validate_python(parsed.get("request_id"))
    except ValidationError:
        return None
