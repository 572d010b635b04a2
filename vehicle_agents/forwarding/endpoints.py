"""The forward's GCS endpoints: one UDP socket towards one GCS, its address and counters,
and the ids heard on each side, which route every frame (see the package's docstring)."""

from __future__ import annotations

import asyncio
import ipaddress
import logging
import socket
from collections.abc import Callable
from dataclasses import dataclass, fields
from typing import Any, Protocol

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from vehicle_agents.fcu.messages import MavMessage

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
