"""The MAVLink link to the flight controller.

pymavlink's connections are blocking, and the URL forms operators know
(``tcp:``, ``udpin:``, ``/dev/ttyACM0,57600``) come from ``mavutil``. So one reader
thread per link blocks on the connection and hands each message to the event loop;
everything else (the cache of the latest message per type, acknowledgement waiters,
sending) happens on the loop thread, which is the only writer.
"""

from __future__ import annotations

import asyncio
import collections
import contextlib
import logging
import struct
import threading
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from typing import Any

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from common.retry import Backoff, Retries
from vehicle_agents.fcu.dialect import mavutil
from vehicle_agents.fcu.messages import (
    FieldOutOfRange,
    LinkChange,
    MavMessage,
    MessagePredicate,
    StatusText,
    is_autopilot,
    next_match,
    raise_closed,
    read_available,
    wire_problems,
)
from vehicle_agents.fcu.modes import ModeTable, mode_table_for

log = logging.getLogger(__name__)

# Messages whose target_system names the sender, not an addressee: ArduPilot fills
# CAMERA_FEEDBACK's with its own system id (AP_Camera::send_feedback), for every GCS.
_SENDER_IN_TARGET = frozenset({"CAMERA_FEEDBACK"})


@dataclass(frozen=True)
class FcuTimeouts:
    """Every wait on the flight controller, named, with defaults."""

    heartbeat_s: float = 3.0  # no heartbeat for this long: the link is lost
    reconnect: Backoff = Backoff(initial_s=0.5, max_s=5.0)
    read_poll_s: float = 0.25  # how often the reader thread checks for shutdown


@dataclass
class LinkCounters:
    messages: int = 0
    # Garbage bytes and bad frames (bad CRC, truncated, unknown id) that were skipped:
    # pymavlink's robust parser turns each into one BAD_DATA message.
    receive_errors: int = 0
    reconnects: int = 0


@dataclass
class FcuLink:
    """One flight controller, seen through its latest messages."""

    url: str
    source_system: int = 254
    source_component: int = mavlink2.MAV_COMP_ID_ONBOARD_COMPUTER
    timeouts: FcuTimeouts = field(default_factory=FcuTimeouts)

    latest: dict[str, MavMessage] = field(default_factory=dict, init=False)
    received_at: dict[str, float] = field(default_factory=dict, init=False)
    statustexts: collections.deque[StatusText] = field(
        default_factory=lambda: collections.deque(maxlen=50), init=False
    )
    counters: LinkCounters = field(default_factory=LinkCounters, init=False)
    target_system: int | None = field(default=None, init=False)
    target_component: int = field(default=1, init=False)
    modes: ModeTable | None = field(default=None, init=False)

    def __post_init__(self) -> None:
        # Called on the event loop with every message from the vehicle.
        self.listeners: list[Callable[[MavMessage], None]] = []
        # Called on the reader thread with every message and its arrival (Unix) time,
        # for work that must see messages exactly as they came (the onboard .tlog).
        self.recorder: Callable[[MavMessage, float], None] | None = None
        # Called on the reader thread with every frame as it came off the wire (its bytes
        # are ``message.get_msgbuf()``; BAD_DATA too), for MAVLink forwarding. Must not block.
        self.taps: list[Callable[[MavMessage], None]] = []
        # Called on the event loop when the link comes up (the target's first heartbeat
        # on a connection) and when it goes down (heartbeat timeout, connection lost).
        self.state_listeners: list[Callable[[LinkChange], None]] = []
        self._up = False
        self._connection: Any = None
        self._collectors: list[tuple[MessagePredicate, asyncio.Queue[MavMessage]]] = []
        self._identified = asyncio.Event()
        self._loop: asyncio.AbstractEventLoop | None = None
        # Messages cross from the reader thread in batches: one loop wake-up per burst
        # rather than per message, which is most of the agent's CPU at 200 messages/s.
        self._inbox: list[MavMessage] = []
        self._inbox_lock = threading.Lock()

    # -- state -------------------------------------------------------------

    @property
    def connected(self) -> bool:
        heartbeat_at = self.received_at.get("HEARTBEAT")
        return (
            self._connection is not None
            and heartbeat_at is not None
            and time.monotonic() - heartbeat_at < self.timeouts.heartbeat_s
        )

    @property
    def up(self) -> bool:
        """Heartbeats are arriving from the vehicle; flips only through ``LinkChange``s."""
        return self._up

    async def wait_identified(self) -> None:
        """Until the first heartbeat from an autopilot has told us who the vehicle is."""
        await self._identified.wait()

    # -- running -----------------------------------------------------------

    async def run(self) -> None:
        """Keep the link up for as long as the task lives: connect, read, reconnect."""
        self._loop = asyncio.get_running_loop()
        retries = Retries(self.timeouts.reconnect)
        while True:
            try:
                self._connection = await asyncio.to_thread(self._open)
            except OSError as error:
                log.warning("flight controller %s unreachable: %s", self.url, error)
                await retries.wait()
                continue
            retries.reset()
            log.info("flight controller link open: %s", self.url)
            stop = threading.Event()
            reason = "connection closed"
            try:
                async with asyncio.TaskGroup() as tasks:
                    tasks.create_task(asyncio.to_thread(self._read_forever, stop))
                    tasks.create_task(self._send_heartbeats())
                    tasks.create_task(self._watch_heartbeats())
            except* OSError as errors:  # TimeoutError (silence) is an OSError too
                reason = str(errors.exceptions[0]) or type(errors.exceptions[0]).__name__
                log.warning("flight controller link lost: %s", reason)
            finally:
                stop.set()
                connection, self._connection = self._connection, None
                with contextlib.suppress(OSError):
                    connection.close()
            # (not reached when the agent is stopping: a shutdown is no lost link)
            self._set_up(False, reason)
            self.counters.reconnects += 1
            await retries.wait()

    def _open(self) -> Any:
        connection = mavutil().mavlink_connection(
            self.url,
            source_system=self.source_system,
            source_component=self.source_component,
            robust_parsing=True,
            autoreconnect=False,
            retries=0,  # our own backoff retries, without pymavlink's blocking sleeps
        )
        # pymavlink reports a closed TCP peer by printing and returning no data; make it
        # an exception so the link is torn down and reopened.
        if hasattr(connection, "handle_eof"):
            connection.handle_eof = raise_closed
            connection.handle_disconnect = raise_closed
        return connection

    def _read_forever(self, stop: threading.Event) -> None:
        assert self._loop is not None
        connection = self._connection
        last_message = time.monotonic()
        while not stop.is_set():
            messages = read_available(connection, self.timeouts.read_poll_s)
            now = time.monotonic()
            arrived_at = time.time()
            for message in messages:
                if message.get_type() != "BAD_DATA":  # a stream of garbage is no link
                    last_message = now
                for tap in self.taps:
                    tap(message)
                if self.recorder is not None:
                    self.recorder(message, arrived_at)
            if messages:
                with self._inbox_lock:
                    wake_loop = not self._inbox
                    self._inbox.extend(messages)
                if wake_loop:
                    self._loop.call_soon_threadsafe(self._deliver_inbox)
            if now - last_message > self.timeouts.heartbeat_s:
                # Serial and UDP links never "close": silence is how they fail.
                raise TimeoutError(
                    f"no valid MAVLink from {self.url} for {self.timeouts.heartbeat_s:g} s"
                )

    async def _send_heartbeats(self) -> None:
        while True:
            self.send(
                mavlink2.MAVLink_heartbeat_message(
                    mavlink2.MAV_TYPE_GCS, mavlink2.MAV_AUTOPILOT_INVALID, 0, 0, 0, 3
                )
            )
            await asyncio.sleep(1.0)

    async def _watch_heartbeats(self) -> None:
        """Down when the vehicle's heartbeats stop, even if other bytes keep coming."""
        while True:
            await asyncio.sleep(self.timeouts.read_poll_s)
            heartbeat_at = self.received_at.get("HEARTBEAT")
            silent = heartbeat_at is None or time.monotonic() - heartbeat_at > (
                self.timeouts.heartbeat_s
            )
            if self._up and silent:
                self._set_up(False, f"no heartbeat for {self.timeouts.heartbeat_s:g} s")

    def _set_up(self, up: bool, reason: str) -> None:
        if up == self._up:
            return
        self._up = up
        if up:
            log.info("flight controller link up: %s", reason)
        else:
            log.warning("flight controller link down: %s", reason)
        change = LinkChange(up, reason)
        for listener in list(self.state_listeners):
            listener(change)

    # -- receiving ---------------------------------------------------------

    def _deliver_inbox(self) -> None:
        with self._inbox_lock:
            batch, self._inbox = self._inbox, []
        for message in batch:
            try:
                self._on_message(message)
            except Exception:
                # One message a listener chokes on must not cost the rest of the batch
                # (the next heartbeat, a COMMAND_ACK) their delivery.
                log.exception("handling %s from the flight controller failed", message.get_type())

    def _on_message(self, message: MavMessage) -> None:
        kind = message.get_type()
        if kind == "BAD_DATA":
            self.counters.receive_errors += 1
            if self.counters.receive_errors == 1 or self.counters.receive_errors % 1000 == 0:
                log.warning(
                    "skipped bad data from the flight controller (%d so far): %s",
                    self.counters.receive_errors,
                    getattr(message, "reason", "?"),
                )
            return
        if kind == "HEARTBEAT" and self.target_system is None and is_autopilot(message):
            self._identify(message)
        if message.get_srcSystem() != self.target_system:
            return
        if kind == "HEARTBEAT" and message.get_srcComponent() != self.target_component:
            # Another component of the vehicle (a MAVLink camera, a gimbal, a companion
            # computer): its heartbeat says nothing of the autopilot's mode or arming, and
            # taken as the autopilot's it would show the vehicle disarmed in flight.
            return
        if kind not in _SENDER_IN_TARGET and getattr(message, "target_system", 0) not in (
            0,
            self.source_system,
        ):
            # An answer to a GCS attached through forwarding: not the agent's to take,
            # or a third party's COMMAND_ACK could complete the agent's own command.
            return
        self.counters.messages += 1
        self.latest[kind] = message
        self.received_at[kind] = time.monotonic()
        if kind == "HEARTBEAT":
            self.modes = self.modes or mode_table_for(message)
            if not self._up and self._connection is not None:
                self._set_up(True, f"heartbeat from system {self.target_system}")
        elif kind == "STATUSTEXT":
            # Trimmed as the joined events are (PX4 ends some texts with a tab).
            text = message.text.rstrip()
            self.statustexts.append(StatusText(time.time(), message.severity, text))
            log.info("FCU: %s", message.text)
        for listener in self.listeners:
            listener(message)
        for predicate, queue in list(self._collectors):
            if predicate(message):
                queue.put_nowait(message)

    def _identify(self, heartbeat: MavMessage) -> None:
        self.target_system = heartbeat.get_srcSystem()
        self.target_component = heartbeat.get_srcComponent()
        self.modes = mode_table_for(heartbeat)
        log.info(
            "flight controller identified: sysid=%d %s %s",
            self.target_system,
            self.modes.autopilot,
            self.modes.vehicle_type,
        )
        self._identified.set()

    @contextlib.contextmanager
    def collect(self, predicate: MessagePredicate) -> Iterator[asyncio.Queue[MavMessage]]:
        """Every matching message from now until the block ends, queued: for exchanges
        with several answers (IN_PROGRESS, then the final ACK), where two can arrive
        together and a waiter registered after the first would miss the second."""
        queue: asyncio.Queue[MavMessage] = asyncio.Queue()
        collector = (predicate, queue)
        self._collectors.append(collector)
        try:
            yield queue
        finally:
            self._collectors.remove(collector)

    async def wait_for(self, predicate: MessagePredicate, within_s: float) -> MavMessage | None:
        """The first message after now that matches, or None after ``within_s`` seconds."""
        with self.collect(predicate) as matches:
            return await next_match(matches, within_s)

    # -- sending -----------------------------------------------------------

    def send(self, message: MavMessage) -> None:
        if self._connection is None:
            raise ConnectionError("flight controller link is down")
        try:
            self._connection.mav.send(message)
        except (OverflowError, struct.error) as error:
            # Packing failed before anything was written: a value its field's wire type
            # cannot hold. The protocol bounds what the hub sends, so this is the second
            # line; it names the field instead of letting the error escape as it is.
            problems = wire_problems(message) or [str(error)]
            raise FieldOutOfRange(message.get_type(), problems) from error

    def write_frame(self, frame: bytes) -> None:
        """Write an encoded MAVLink frame (a forwarded GCS's) to the vehicle unchanged."""
        if self._connection is None:
            raise ConnectionError("flight controller link is down")
        self._connection.write(frame)

    def send_command_long(self, command: int, confirmation: int, params: list[float]) -> None:
        padded = [float(value) for value in params] + [0.0] * (7 - len(params))
        self.send(
            mavlink2.MAVLink_command_long_message(
                self.target_system or 1,
                self.target_component,
                command,
                confirmation,
                *padded,
            )
        )
