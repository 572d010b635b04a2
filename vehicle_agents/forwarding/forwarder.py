"""The forward itself: frames from the flight controller to every GCS endpoint that should
have them, a GCS's frames to the vehicle, and rate requests through the merger."""

from __future__ import annotations

import asyncio
import contextlib
import logging
import math
import threading
from collections.abc import Callable, Sequence
from typing import Any

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from vehicle_agents.fcu.messages import MavMessage
from vehicle_agents.fcu.rate_merger import RateMerger
from vehicle_agents.fcu.stream_plan import StreamRequest
from vehicle_agents.forwarding.endpoints import (
    READS_PER_WAKEUP,
    REPORT_INTERVAL_S,
    Endpoint,
    EndpointAddress,
    Heard,
    Ids,
    VehicleLink,
    source,
    targets,
)

log = logging.getLogger(__name__)


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
