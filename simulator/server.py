"""The simulator's MAVLink transport: a TCP server or a UDP socket, on asyncio.

Like SITL's port 5760, the TCP server takes any number of clients; each gets its own
stream and its own sequence numbers (`simulator/mavlink/peer_links.py`). The UDP socket
answers every address it has heard from.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import time
from collections.abc import Callable
from dataclasses import replace
from typing import TYPE_CHECKING, Any

from simulator.clock import Clock, SimClock
from simulator.config import ListenAddress, SimulatorConfig
from simulator.mavconst import MsgId
from simulator.mavlink.commands import MessageHandler
from simulator.mavlink.message_context import MavMessage, SecondGps
from simulator.mavlink.peer_links import COMPONENT_ID, Link, TcpLink, UdpLink
from simulator.mavlink.streams import StreamRequests, StreamSchedule
from simulator.mavlink.telemetry import DEFAULT_RATES_HZ, TelemetryBuilder
from simulator.outputs.camera_outputs import CameraOutputs
from simulator.vehicle import ItemReached, PhotoTaken, Vehicle
from simulator.vehicles import REBOOT_SILENCE_S, build_vehicle

if TYPE_CHECKING:
    from simulator.outputs.lidar import LidarStream

log = logging.getLogger(__name__)

TICK_S = 0.01  # wall seconds between physics catch-ups and stream checks, at most
# ... and at least: a stream due sooner in sim time (a speed-up) brings the tick forward,
# down to this, and so does one running late, to catch up
MIN_TICK_S = 0.001
READ_SIZE = 4096


class _UdpProtocol(asyncio.DatagramProtocol):
    def __init__(self, server: SimulatorServer) -> None:
        self.server = server

    def datagram_received(self, data: bytes, addr: Any) -> None:
        self.server._on_datagram(data, addr)

    def error_received(self, exc: Exception) -> None:
        # e.g. ICMP port unreachable from a peer that went away
        log.debug("udp: %s", exc)


class SimulatorServer:
    """One simulated vehicle on one listening address."""

    def __init__(
        self,
        config: SimulatorConfig,
        *,
        clock: Clock | None = None,
        copter: Vehicle | None = None,
        wall_clock: Callable[[], float] = time.monotonic,
    ) -> None:
        self.config = config
        self.clock: Clock = clock if clock is not None else SimClock(config.speedup)
        self.copter = copter if copter is not None else build_vehicle(config)
        gps2 = None if config.gps2_fix is None else SecondGps(config.gps2_fix)
        self.telemetry = TelemetryBuilder(self.copter, boot_epoch_s=time.time(), gps2=gps2)
        self.handler = StreamRequests(
            MessageHandler(self.copter, self.telemetry, config.system_id, COMPONENT_ID),
            config.message_interval,
        )
        self.links: list[Link] = []
        self.address: ListenAddress | None = None
        self._wall = wall_clock
        self._tcp_server: asyncio.Server | None = None
        self._udp_transport: asyncio.DatagramTransport | None = None
        self._udp_links: dict[Any, UdpLink] = {}
        self._client_tasks: set[asyncio.Task[None]] = set()
        self._ticker: asyncio.Task[None] | None = None
        self._signature = self._state_signature()
        self._silent_until = 0.0  # a rebooting flight controller neither hears nor sends
        self.lidar: LidarStream | None = None
        self.lidar_address: ListenAddress | None = None
        self.cameras = CameraOutputs(config, self._broadcast)

    # -- lifecycle -------------------------------------------------------------

    async def start(self) -> ListenAddress:
        """Bind and start simulating; returns the bound address (port 0 resolved)."""
        listen = self.config.listen
        loop = asyncio.get_running_loop()
        if listen.scheme == "tcp":
            self._tcp_server = await asyncio.start_server(
                self._on_tcp_client, listen.host, listen.port
            )
            port = int(self._tcp_server.sockets[0].getsockname()[1])
        else:
            transport, _ = await loop.create_datagram_endpoint(
                lambda: _UdpProtocol(self), local_addr=(listen.host, listen.port)
            )
            self._udp_transport = transport
            port = int(transport.get_extra_info("sockname")[1])
        self.address = ListenAddress(listen.scheme, listen.host, port)
        if self.config.lidar is not None:
            # numpy is imported only by a simulator that has a LIDAR to ray-cast for
            from simulator.outputs.lidar import LidarStream

            self.lidar = LidarStream(
                self.config.lidar,
                self.config.scene,
                self.config.lidar_rate_hz,
                seed=self.config.system_id,
                wire=self.config.lidar_format,
            )
            self.lidar_address = await self.lidar.start()
        await self.cameras.start(self.telemetry.boot_epoch_s)
        self._ticker = asyncio.create_task(self._tick_forever(), name="simulator-tick")
        log.info(
            "simulator sysid=%d listening on %s speedup=%g",
            self.config.system_id,
            self.address,
            self.config.speedup,
        )
        return self.address

    async def stop(self) -> None:
        """Stop listening, close every client, stop the clock."""
        if self._ticker is not None:
            self._ticker.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await self._ticker
            self._ticker = None
        if self._tcp_server is not None:
            self._tcp_server.close()
        if self.lidar is not None:
            await self.lidar.stop()
        await self.cameras.stop()
        for link in list(self.links):
            link.close()
        if self._client_tasks:
            await asyncio.wait(self._client_tasks, timeout=2.0)
        if self._tcp_server is not None:
            await self._tcp_server.wait_closed()
            self._tcp_server = None
        if self._udp_transport is not None:
            self._udp_transport.close()
            self._udp_transport = None
        self.links.clear()
        self._udp_links.clear()
        log.info("simulator sysid=%d stopped", self.config.system_id)

    async def serve(self, stop: asyncio.Event) -> None:
        """Run until ``stop`` is set."""
        await self.start()
        try:
            await stop.wait()
        finally:
            await self.stop()

    # -- simulation ------------------------------------------------------------

    async def _tick_forever(self) -> None:
        while True:
            self.tick()
            await asyncio.sleep(self._until_next_tick())

    def _until_next_tick(self) -> float:
        """Wall seconds to sleep: until the next stream is due in sim time, so that a
        speed-up multiplies the rates per wall second (as SITL's SIM_SPEEDUP does) rather
        than capping them at one message a tick; TICK_S at most, for the physics, and
        through a reboot's silence (the streams wait, late, for its end)."""
        if self._wall() < self._silent_until:
            return TICK_S
        dues = [due for link in self.links if (due := link.streams.next_due()) is not None]
        if not dues:
            return TICK_S
        wait = (min(dues) - self.clock.now()) / self.config.speedup
        return min(TICK_S, max(MIN_TICK_S, wait))

    def tick(self) -> None:
        """Catch the physics up with the clock and send whatever streams are due.

        The streams are timed in sim time; the silence of a reboot and the camera
        component's heartbeat in wall time (what the agent's link timeouts measure)."""
        wall = self._wall()
        now = self.clock.now()
        self.copter.advance_to(now)
        if self.lidar is not None:  # the sensor has its own power: it turns through a reboot
            self.lidar.advance(self.copter)
        if wall < self._silent_until:
            return
        self._publish_changes(now)
        self.cameras.tick(wall)
        built: dict[int, MavMessage] = {}
        for link in list(self.links):
            for msg_id in link.streams.due(now):
                if msg_id not in built:
                    built[msg_id] = self.telemetry.build(msg_id)
                message = built[msg_id]
                if message is not None:
                    link.send(message)

    def _publish_changes(self, now: float) -> None:
        for text in self.copter.drain_texts():
            log.info("STATUSTEXT %s: %s", text.severity.name, text.text)
            self._broadcast(self.telemetry.statustext(text))
        for event in self.copter.drain_events():
            if isinstance(event, ItemReached):
                on_wire = event.seq - self.copter.mission_wire_offset
                self._broadcast(self.telemetry.mission_item_reached(on_wire))
            else:
                self._photo_taken(event)
        signature = self._state_signature()
        if signature != self._signature:
            # ArduCopter sends a HEARTBEAT straight away when its mode changes
            mode_changed = signature[0] != self._signature[0]
            self._signature = signature
            for link in self.links:
                link.streams.send_soon(MsgId.HEARTBEAT, now)
            if mode_changed and self.telemetry.sends_current_mode:
                self._broadcast(self.telemetry.current_mode())  # PX4: on each change

    def _photo_taken(self, photo: PhotoTaken) -> None:
        """The camera fired: told as the autopilot tells of it (see `personality`), and
        as the camera itself does where it is a component or fills a folder."""
        px4 = self.telemetry.sends_camera_trigger
        if px4:
            photo = replace(photo, index=photo.index - 1)  # PX4's sequence starts at 0
        self.cameras.serve_photo(photo)  # before the feedback: the agent fetches on it
        if not px4:
            self._broadcast(self.telemetry.camera_feedback(photo))
        else:
            trigger = self.telemetry.camera_trigger(photo)
            for link in list(self.links):
                if link.streams.interval(MsgId.CAMERA_TRIGGER) is not None:
                    link.send(trigger)
            self._broadcast(self.telemetry.camera_image_captured(photo))
        self.cameras.camera_shot(photo)

    def _state_signature(self) -> tuple[int, bool, int]:
        copter = self.copter
        return copter.custom_mode(), copter.armed, int(copter.system_status())

    def _reboot(self, wall: float) -> None:
        """The flight controller restarts: silence (wall seconds), then a fresh boot of the
        same vehicle, with every link back on the default streams."""
        self._silent_until = wall + REBOOT_SILENCE_S
        now = self.clock.now()
        self.copter = self.copter.rebooted(boot_at=now)
        self.telemetry = TelemetryBuilder(
            self.copter, boot_epoch_s=time.time(), gps2=self.telemetry.gps2
        )
        self.handler = StreamRequests(
            MessageHandler(self.copter, self.telemetry, self.config.system_id, COMPONENT_ID),
            self.config.message_interval,
        )
        for link in self.links:
            # all due when the silence ends (the first tick after it finds them late)
            link.streams = StreamSchedule(DEFAULT_RATES_HZ, now)
        self.cameras.restart(self.telemetry.boot_epoch_s)
        self._signature = self._state_signature()
        log.info("simulator sysid=%d rebooting", self.config.system_id)

    def _broadcast(self, message: MavMessage, component: int = COMPONENT_ID) -> None:
        for link in list(self.links):
            link.send(message, component)

    # -- receiving -------------------------------------------------------------

    def _receive(self, link: Link, data: bytes) -> None:
        wall = self._wall()
        if wall < self._silent_until:
            return
        now = self.clock.now()
        self.copter.advance_to(now)  # commands act on the current state
        for message in link.decode(data):
            for reply in self.handler.handle(message, link.streams, now):
                if reply.to_sender_only:
                    link.send(reply.message)
                else:
                    self._broadcast(reply.message)
        self._publish_changes(now)
        if self.copter.reboot_requested:  # acknowledged above; now it restarts
            self._reboot(wall)

    async def _on_tcp_client(
        self, reader: asyncio.StreamReader, writer: asyncio.StreamWriter
    ) -> None:
        task = asyncio.current_task()
        if task is not None:
            self._client_tasks.add(task)
        peer = writer.get_extra_info("peername")
        link = TcpLink(f"tcp client {peer}", self.config.system_id, self.clock.now(), writer)
        self.links.append(link)
        log.info("client connected: %s", peer)
        try:
            while data := await reader.read(READ_SIZE):
                self._receive(link, data)
        except (ConnectionError, OSError) as error:
            log.debug("client %s: %s", peer, error)
        finally:
            if link in self.links:
                self.links.remove(link)
            writer.close()
            with contextlib.suppress(ConnectionError, OSError):
                await writer.wait_closed()
            log.info("client disconnected: %s", peer)
            if task is not None:
                self._client_tasks.discard(task)

    def _on_datagram(self, data: bytes, address: Any) -> None:
        link = self._udp_links.get(address)
        if link is None:
            assert self._udp_transport is not None
            link = UdpLink(
                f"udp peer {address}",
                self.config.system_id,
                self.clock.now(),
                self._udp_transport,
                address,
            )
            self._udp_links[address] = link
            self.links.append(link)
            log.info("udp peer: %s", address)
        self._receive(link, data)
