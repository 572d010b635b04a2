"""MAVLink forwarding: third-party GCSs (QGroundControl, MAVProxy) reach the vehicle
through the agent, as they would through mavlink-router, while the hub keeps its view.

Each endpoint is one UDP socket towards one GCS. ``udpout:HOST:PORT`` sends to a fixed
address (QGroundControl listens on 14550); ``udpin:HOST:PORT`` listens, and answers the
address the GCS last wrote from. Frames are routed by the ids they carry, with
mavlink-router's rules (``Endpoint::accept_msg``):

- a frame never goes back where its source has been heard from (no loops);
- a frame without a target, or for system 0, goes everywhere else;
- a frame for system S, component C, goes only where S/C has been heard from (where S
  has, if C is 0 or absent). Towards the flight controller the system is enough: the
  autopilot routes on to its own components.

So the vehicle's telemetry reaches every GCS, a GCS's command reaches the vehicle, the
answer reaches only the GCS that asked, and the agent's own exchanges with the vehicle
(addressed to its ``source_system``) reach no GCS. A frame that comes back carrying the
autopilot's own ids is a routing loop: it is dropped and counted.

Rate requests are the exception: the flight controller keeps one set of stream rates per
link, shared by the agent and every GCS behind it, so a GCS's REQUEST_DATA_STREAM and
SET_MESSAGE_INTERVAL (COMMAND_LONG or COMMAND_INT) go through ``RateMerger``
(streams.py): the flight controller is sent the highest rate each stream needs, once, and
a SET_MESSAGE_INTERVAL asking for no more than is already set is answered ACCEPTED here,
on the autopilot's behalf, and not sent on. Otherwise MAVProxy's REQUEST_DATA_STREAM every
~15 s lowered the agent's position rate, and the two asked in turn forever.

Other frames travel unchanged (their sequence numbers and signatures too). The vehicle's are
sent from the FCU reader thread, through a tap, with a non-blocking ``sendto``: there is
no queue and no thread per GCS, a datagram the kernel will not take is dropped and
counted, and a GCS that is gone can never stall the reader. A GCS's frames are read on the
event loop and written to the vehicle there, like the agent's own.
"""

from __future__ import annotations

import asyncio
import contextlib
import ipaddress
import logging
import math
import socket
import threading
from collections.abc import Callable, Sequence
from dataclasses import dataclass, fields
from typing import Any, Protocol

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from vehicle_agents.fcu_link import MavMessage
from vehicle_agents.streams import RateMerger, StreamRequest

log = logging.getLogger(__name__)

NO_TARGET = -1  # the message has no such field: as good as a broadcast
MAX_DATAGRAM = 65535
READS_PER_WAKEUP = 64  # datagrams taken from one socket per wake-up, so no GCS hogs the loop
REPORT_INTERVAL_S = 60.0  # how often trouble (drops, loops, bad bytes) is logged

Ids = tuple[int, int]  # (system id, component id)


class VehicleLink(Protocol):
    """What forwarding needs of the flight controller link (``FcuLink``)."""

    source_system: int
    source_component: int
    target_system: int | None
    target_component: int
    taps: list[Callable[[MavMessage], None]]

    def write_frame(self, frame: bytes) -> None: ...

    def send(self, message: MavMessage) -> None: ...

    def send_command_long(self, command: int, confirmation: int, params: list[float]) -> None: ...


@dataclass(frozen=True)
class EndpointAddress:
    """``udpin:HOST:PORT`` (listen there) or ``udpout:HOST:PORT`` (send there)."""

    listen: bool
    host: str
    port: int

    @classmethod
    def parse(cls, text: str) -> EndpointAddress:
        mode, _, rest = text.strip().partition(":")
        host, _, port = rest.rpartition(":")
        host = host.removeprefix("[").removesuffix("]")  # [::1]
        if mode not in ("udpin", "udpout") or not host or not port.isdigit():
            raise ValueError(
                f"MAVLink forwarding endpoint {text!r}: expected udpin:HOST:PORT "
                "(listen for a GCS) or udpout:HOST:PORT (send to a GCS)"
            )
        if not 0 < int(port) < 65536:
            raise ValueError(f"MAVLink forwarding endpoint {text!r}: port out of range")
        return cls(mode == "udpin", host, int(port))

    def __str__(self) -> str:
        host = f"[{self.host}]" if ":" in self.host else self.host
        return f"{'udpin' if self.listen else 'udpout'}:{host}:{self.port}"


class Heard:
    """The ids heard from one side of the router: where frames for them go."""

    def __init__(self) -> None:
        self.components: set[Ids] = set()
        self.systems: set[int] = set()

    def add(self, ids: Ids) -> bool:
        """Remember ``ids``; True if they are new here."""
        if ids in self.components:
            return False
        self.components.add(ids)
        self.systems.add(ids[0])
        return True

    def clear(self) -> None:
        self.components.clear()
        self.systems.clear()

    def wants(self, source: Ids, target_system: int, target_component: int) -> bool:
        """Whether a frame goes out this way: mavlink-router's rule."""
        if source in self.components:
            return False
        if target_system in (NO_TARGET, 0):
            return True
        if target_component > 0:
            return (target_system, target_component) in self.components
        return target_system in self.systems

    def wants_system(self, source: Ids, target_system: int) -> bool:
        """The same rule by system only, for a side that routes on to its own components."""
        if source in self.components:
            return False
        return target_system in (NO_TARGET, 0) or target_system in self.systems


def targets(message: MavMessage) -> tuple[int, int]:
    """The (system, component) a message is addressed to; ``NO_TARGET`` where it has no
    such field. MAVLink 2 trims trailing zeros; pymavlink restores them, as 0."""
    return (
        int(getattr(message, "target_system", NO_TARGET)),
        int(getattr(message, "target_component", NO_TARGET)),
    )


def source(message: MavMessage) -> Ids:
    return int(message.get_srcSystem()), int(message.get_srcComponent())


def _parser() -> Any:
    parser = mavlink2.MAVLink(None)
    parser.robust_parsing = True
    return parser


@dataclass
class EndpointCounters:
    sent: int = 0  # frames sent to the GCS (the vehicle's, or another GCS's)
    dropped: int = 0  # frames the socket refused, or the GCS's the vehicle link could not take
    received: int = 0  # valid MAVLink frames from the GCS
    to_vehicle: int = 0  # of those, written to the flight controller
    unrouted: int = 0  # of those, addressed to nobody heard from (or to the agent itself)
    looped: int = 0  # of those, carrying the autopilot's own ids: a routing loop
    bad_frames: int = 0  # bytes from the GCS that were not valid MAVLink
    peer_changes: int = 0  # a udpin endpoint's GCS wrote from a new address

    def as_dict(self) -> dict[str, int]:
        return {f.name: getattr(self, f.name) for f in fields(self)}


def _source_host(family: int, destination: str) -> str:
    """Where a udpout socket listens for the GCS's answers: loopback for a GCS on this
    computer, every interface otherwise (the route picks the source address)."""
    if ipaddress.ip_address(destination.split("%")[0]).is_loopback:
        return "::1" if family == socket.AF_INET6 else "127.0.0.1"
    return "::" if family == socket.AF_INET6 else "0.0.0.0"


class Endpoint:
    """One UDP socket towards one GCS."""

    def __init__(self, address: EndpointAddress) -> None:
        self.address = address
        self.peer: Any = None  # where frames for the GCS go: fixed (udpout) or learnt (udpin)
        self.heard = Heard()
        self.counters = EndpointCounters()
        self.local_address: Any = None
        self._socket: socket.socket | None = None
        self._parser = _parser()
        self._failing = False
        self._reported = EndpointCounters()

    async def open(self) -> None:
        loop = asyncio.get_running_loop()
        infos = await loop.getaddrinfo(self.address.host, self.address.port, type=socket.SOCK_DGRAM)
        family, _, _, _, address = infos[0]
        sock = socket.socket(family, socket.SOCK_DGRAM)
        try:
            sock.setblocking(False)
            if self.address.listen:
                sock.bind(address)
            else:
                # Bound now, so the GCS's answers (to the port it sees us send from) are read.
                # To a GCS on this computer, from loopback only: a wildcard port would take
                # frames from any host on the network straight to the flight controller.
                sock.bind((_source_host(family, str(address[0])), 0))
                self.peer = address
        except OSError:
            sock.close()
            raise
        self.local_address = sock.getsockname()
        self._socket = sock

    def fileno(self) -> int:
        return -1 if self._socket is None else self._socket.fileno()

    def close(self) -> None:
        sock, self._socket = self._socket, None
        if sock is not None:
            sock.close()

    def deliver(self, frame: bytes) -> None:
        """Send one frame to the GCS now, or drop it: never waits. Caller holds the lock."""
        sock, peer = self._socket, self.peer
        if sock is None or peer is None:
            return  # no GCS yet (udpin before its first frame): nobody to lose it
        try:
            sock.sendto(frame, peer)
        except OSError as error:  # buffer full, network unreachable, closed meanwhile...
            self.counters.dropped += 1
            if not self._failing:
                self._failing = True
                log.warning("MAVLink forwarding to %s (%s): %s; dropping", self, peer, error)
            return
        self.counters.sent += 1
        if self._failing:
            self._failing = False
            log.info("MAVLink forwarding to %s works again", self)

    def parse(self, data: bytes) -> list[MavMessage]:
        """The frames in one datagram. A datagram holds whole frames: bytes left over are
        garbage, and must not swallow the start of the next datagram."""
        try:
            messages = self._parser.parse_buffer(data) or []
            broken = self._parser.buf_len() > 0
        except mavlink2.MAVError as error:  # a few malformed frames raise even when robust
            log.debug("%s: undecodable bytes: %s", self, error)
            messages, broken = [], True
        if broken:
            self.counters.bad_frames += 1
            self._parser = _parser()
        good = [m for m in messages if m.get_type() != "BAD_DATA"]
        self.counters.bad_frames += len(messages) - len(good)
        return good

    def receive(self) -> tuple[bytes, Any] | None:
        if self._socket is None:
            return None
        try:
            return self._socket.recvfrom(MAX_DATAGRAM)
        except (BlockingIOError, InterruptedError):
            return None
        except OSError as error:  # e.g. an ICMP error reported on the socket
            log.debug("%s: %s", self, error)
            return None

    def trouble_since_report(self) -> dict[str, int]:
        """Drops, loops and bad bytes since the last call (each logged, not each frame)."""
        now, before = self.counters, self._reported
        trouble = {
            name: getattr(now, name) - getattr(before, name)
            for name in ("dropped", "looped", "bad_frames", "peer_changes")
            if getattr(now, name) != getattr(before, name)
        }
        self._reported = EndpointCounters(**now.as_dict())
        return trouble

    def __str__(self) -> str:
        return str(self.address)


class MavlinkForwarder:
    """Routes MAVLink between the flight controller and third-party GCS endpoints."""

    def __init__(
        self, link: VehicleLink, endpoints: Sequence[str], merger: RateMerger | None = None
    ) -> None:
        self.link = link
        # The agent's StreamRequester shares it: the agent's own rates are merged in too.
        self.merger = merger if merger is not None else RateMerger()
        self.endpoints = [Endpoint(EndpointAddress.parse(text)) for text in endpoints]
        self.vehicle = Heard()  # the ids heard from the flight controller's side
        self._open: list[Endpoint] = []
        # The FCU reader thread and the event loop both route: this guards the heard ids,
        # the open endpoints and the counters. Held only for in-memory work and UDP sendto,
        # never while writing to the flight controller.
        self._lock = threading.Lock()
        self._tap: Callable[[MavMessage], None] = self.from_vehicle

    async def run(self) -> None:
        """Forward until cancelled; an endpoint that cannot open is logged and left out."""
        loop = asyncio.get_running_loop()
        opened: list[Endpoint] = []
        try:
            for endpoint in self.endpoints:
                try:
                    await endpoint.open()
                except OSError as error:
                    log.error("MAVLink forwarding to %s disabled: %s", endpoint, error)
                    continue
                loop.add_reader(endpoint.fileno(), self._on_readable, endpoint)
                opened.append(endpoint)
                log.info("MAVLink forwarding: %s (local %s)", endpoint, endpoint.local_address)
            with self._lock:
                self._open = opened
            self.link.taps.append(self._tap)
            while True:
                await asyncio.sleep(REPORT_INTERVAL_S)
                self._report_trouble()
        finally:
            with contextlib.suppress(ValueError):
                self.link.taps.remove(self._tap)
            with self._lock:
                self._open = []
            for endpoint in opened:
                loop.remove_reader(endpoint.fileno())
                endpoint.close()
                log.info("MAVLink forwarding to %s stopped: %s", endpoint, endpoint.counters)

    # -- the vehicle's frames (FCU reader thread) ---------------------------

    def from_vehicle(self, message: MavMessage) -> None:
        """The tap: one frame from the flight controller, to every GCS it is for."""
        if message.get_type() == "BAD_DATA":
            return
        frame = message.get_msgbuf()
        ids = source(message)
        target_system, target_component = targets(message)
        with self._lock:
            self.vehicle.add(ids)
            for endpoint in self._open:
                if endpoint.heard.wants(ids, target_system, target_component):
                    endpoint.deliver(frame)

    # -- a GCS's frames (event loop) ----------------------------------------

    def _on_readable(self, endpoint: Endpoint) -> None:
        for _ in range(READS_PER_WAKEUP):
            received = endpoint.receive()
            if received is None:
                return
            self.from_gcs(endpoint, *received)

    def from_gcs(self, endpoint: Endpoint, data: bytes, address: Any) -> None:
        """One datagram from a GCS: learn who sent it, then route each frame in it."""
        messages = endpoint.parse(data)
        if messages and endpoint.address.listen and address != endpoint.peer:
            self._new_peer(endpoint, address)  # only MAVLink makes a peer, not stray bytes
        for message in messages:
            frame = message.get_msgbuf()
            ids = source(message)
            target_system, target_component = targets(message)
            with self._lock:
                endpoint.counters.received += 1
                if ids in self.vehicle.components:
                    endpoint.counters.looped += 1
                    continue
                if endpoint.heard.add(ids):
                    self._check_new_ids(endpoint, ids)
                to_vehicle = self.vehicle.wants_system(ids, target_system)
                routed = to_vehicle
                for other in self._open:
                    if other is not endpoint and other.heard.wants(
                        ids, target_system, target_component
                    ):
                        other.deliver(frame)
                        routed = True
                if not routed:
                    endpoint.counters.unrouted += 1
            if to_vehicle and not self._rate_request(endpoint, message, ids, target_system):
                self._to_vehicle(endpoint, frame)

    def _rate_request(
        self, endpoint: Endpoint, message: MavMessage, ids: Ids, target_system: int
    ) -> bool:
        """A GCS's stream-rate request, merged; True when it was dealt with here (the
        merged rates sent, the GCS answered), False when its frame goes on as it is."""
        if target_system not in (0, self.link.target_system):
            return False  # another system's: not this flight controller's rates
        kind = message.get_type()
        try:
            if kind == "REQUEST_DATA_STREAM":
                if message.start_stop not in (0, 1):
                    return False  # ArduPilot ignores it: let it
                changed = self.merger.data_stream(
                    ids,
                    int(message.req_stream_id),
                    int(message.req_message_rate),
                    message.start_stop == 1,
                )
                target = (self.link.target_system or 1, self.link.target_component)
                for group, rate in changed.items():
                    self.link.send(
                        mavlink2.MAVLink_request_data_stream_message(
                            *target, group, rate, 1 if rate > 0 else 0
                        )
                    )
                return True
            if (
                kind in ("COMMAND_LONG", "COMMAND_INT")
                and message.command == mavlink2.MAV_CMD_SET_MESSAGE_INTERVAL
                and math.isfinite(message.param1)
                and math.isfinite(message.param2)
            ):
                msg_id = int(message.param1)
                answer = self.merger.message_interval(ids, msg_id, float(message.param2))
                if answer.forward:
                    return False
                if answer.send_hz is not None:
                    merged = StreamRequest("", msg_id, answer.send_hz)
                    self.link.send_command_long(
                        mavlink2.MAV_CMD_SET_MESSAGE_INTERVAL, 0, [msg_id, merged.interval_us]
                    )
                self._answer(endpoint, ids, mavlink2.MAV_CMD_SET_MESSAGE_INTERVAL)
                return True
        except (ConnectionError, OSError) as error:
            with self._lock:
                endpoint.counters.dropped += 1
            log.debug("%s: rate request for the vehicle dropped: %s", endpoint, error)
            return True
        return False

    def _answer(self, endpoint: Endpoint, ids: Ids, command: int) -> None:
        """COMMAND_ACK ACCEPTED to the GCS, from the autopilot's ids, as it would answer."""
        sender = mavlink2.MAVLink(
            None, self.link.target_system or 1, self.link.target_component or 1
        )
        ack = mavlink2.MAVLink_command_ack_message(
            command, mavlink2.MAV_RESULT_ACCEPTED, 0, 0, ids[0], ids[1]
        )
        with self._lock:
            endpoint.deliver(ack.pack(sender))

    def _to_vehicle(self, endpoint: Endpoint, frame: bytes) -> None:
        try:
            self.link.write_frame(frame)
        except (ConnectionError, OSError) as error:
            with self._lock:
                endpoint.counters.dropped += 1
            log.debug("%s: frame for the vehicle dropped: %s", endpoint, error)
            return
        with self._lock:
            endpoint.counters.to_vehicle += 1

    def _new_peer(self, endpoint: Endpoint, address: Any) -> None:
        """A udpin endpoint's GCS appeared, restarted (a new source port), or another GCS
        took the port over: answer the new address, and relearn its ids."""
        if endpoint.peer is None:
            log.info("MAVLink forwarding %s: GCS at %s", endpoint, address)
        elif endpoint.counters.peer_changes == 0:
            log.info(
                "MAVLink forwarding %s: GCS now at %s (was %s)", endpoint, address, endpoint.peer
            )
        with self._lock:
            if endpoint.peer is not None:
                endpoint.counters.peer_changes += 1  # many: two GCSs on one udpin endpoint
            endpoint.peer = address
            endpoint.heard.clear()

    def _check_new_ids(self, endpoint: Endpoint, ids: Ids) -> None:
        """Warn about id clashes that make answers go astray; caller holds the lock."""
        if ids[0] == self.link.source_system:
            log.warning(
                "MAVLink forwarding %s: a GCS uses the agent's own system id %d; the "
                "vehicle's answers to one may reach the other. Give the GCS another id "
                "(QGroundControl: Application Settings > MAVLink) or the agent another "
                "source_system",
                endpoint,
                ids[0],
            )
        for other in self._open:
            if other is not endpoint and ids in other.heard.components:
                log.warning(
                    "MAVLink forwarding: ids %d/%d heard on both %s and %s; answers to them "
                    "go to both",
                    *ids,
                    other,
                    endpoint,
                )

    def _report_trouble(self) -> None:
        with self._lock:
            troubles = [(endpoint, endpoint.trouble_since_report()) for endpoint in self._open]
        for endpoint, trouble in troubles:
            if trouble:
                log.warning(
                    "MAVLink forwarding %s in the last %.0f s: %s (totals %s)",
                    endpoint,
                    REPORT_INTERVAL_S,
                    ", ".join(f"{count} {name}" for name, count in trouble.items()),
                    endpoint.counters,
                )
