"""The simulator's MAVLink peers: each with its own parser, its own encoders (sequence
numbers) and its own streams, over a TCP connection or a UDP address.

pymavlink serves only as a codec here (never ``mavutil``): one parser and one encoder
per peer and component.
"""

from __future__ import annotations

import asyncio
import logging
from abc import ABC, abstractmethod
from typing import Any

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from simulator.mavlink.message_context import MavMessage
from simulator.mavlink.streams import StreamSchedule
from simulator.mavlink.telemetry import DEFAULT_RATES_HZ

log = logging.getLogger(__name__)

COMPONENT_ID = 1  # MAV_COMP_ID_AUTOPILOT1
MAX_PENDING_BYTES = 256 * 1024  # a client this far behind loses messages, not memory


class Link(ABC):
    """One MAVLink peer: its parser, its encoder (sequence numbers) and its streams."""

    def __init__(self, name: str, system_id: int, now: float) -> None:
        self.name = name
        self._parser: Any = mavlink2.MAVLink(None, srcSystem=system_id, srcComponent=COMPONENT_ID)
        self._parser.robust_parsing = True
        self._system_id = system_id
        # One encoder (sequence numbers) per component that speaks on this link: the
        # autopilot, and the camera where it is a MAVLink camera component.
        self._encoders: dict[int, Any] = {}
        self.streams = StreamSchedule(DEFAULT_RATES_HZ, now)
        self.bad_frames = 0

    def decode(self, data: bytes) -> list[Any]:
        try:
            messages = self._parser.parse_buffer(data) or []
        except Exception as error:  # pymavlink raises on a few malformed frames
            log.debug("%s: undecodable bytes: %s", self.name, error)
            self.bad_frames += 1
            return []
        good = [m for m in messages if m.get_type() != "BAD_DATA"]
        self.bad_frames += len(messages) - len(good)
        return good

    def send(self, message: MavMessage, component: int = COMPONENT_ID) -> None:
        encoder = self._encoders.get(component)
        if encoder is None:
            encoder = mavlink2.MAVLink(None, srcSystem=self._system_id, srcComponent=component)
            self._encoders[component] = encoder
        frame: bytes = message.pack(encoder)
        encoder.seq = (encoder.seq + 1) % 256
        self._write(frame)

    @abstractmethod
    def _write(self, frame: bytes) -> None: ...

    @abstractmethod
    def close(self) -> None:
        """Release the peer."""


class TcpLink(Link):
    def __init__(self, name: str, system_id: int, now: float, writer: asyncio.StreamWriter):
        super().__init__(name, system_id, now)
        self.writer = writer
        self.dropped = 0

    def _write(self, frame: bytes) -> None:
        transport = self.writer.transport
        if transport.is_closing():
            return
        if transport.get_write_buffer_size() > MAX_PENDING_BYTES:
            self.dropped += 1
            return
        self.writer.write(frame)

    def close(self) -> None:
        self.writer.close()


class UdpLink(Link):
    def __init__(
        self,
        name: str,
        system_id: int,
        now: float,
        transport: asyncio.DatagramTransport,
        address: Any,
    ) -> None:
        super().__init__(name, system_id, now)
        self.transport = transport
        self.address = address

    def _write(self, frame: bytes) -> None:
        if not self.transport.is_closing():
            self.transport.sendto(frame, self.address)

    def close(self) -> None:
        """UDP peers share the server's socket: nothing of their own to close."""
