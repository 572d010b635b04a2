"""The simulated LIDAR's serial line, served over TCP: every client gets the sensor's bytes.

A real LIDAR is a serial port; here the same bytes go to whoever connects (the agent's
driver reads ``tcp://HOST:PORT`` as it reads ``/dev/ttyUSB0``). The bytes are those of the
wire format chosen (simulator/wire/formats.py lists them). Like the sensor, a connection
to a Slamtec or YDLIDAR format idles until it sends a start command, and is answered
its other commands (information, health, stop), so the driver's start-up is exercised
too; an LDROBOT format sends from the moment of connection, as that sensor does from
power-up. A client that falls behind loses bytes, as a serial port's receive buffer
would overflow, never the simulator's memory; the parser resynchronises on the next
packet.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
from pathlib import Path

from simulator.config import ListenAddress
from simulator.sensors.lidar import Lidar, LidarSpec, Pose
from simulator.vehicle import Vehicle
from simulator.wire import ldlidar as ldlidar_wire
from simulator.wire import rplidar as rplidar_wire
from simulator.wire import ydlidar as ydlidar_wire
from simulator.wire.formats import LIDAR_FORMATS, Encoder, Reply, Start, Stop, WireFormat
from simulator.world.obstacles import World, default_scene, load_scene

log = logging.getLogger(__name__)

MAX_PENDING_BYTES = 64 * 1024  # about 2 s of a T-mini Pro's output


def wire_format(name: str) -> WireFormat:
    if name.startswith("rplidar"):
        return rplidar_wire.wire_format(name)
    if name.startswith("ydlidar"):
        return ydlidar_wire.wire_format(name)
    if name == "ld06":
        return ldlidar_wire.wire_format(name)
    raise ValueError(f"unknown LIDAR format {name!r}; known: {', '.join(LIDAR_FORMATS)}")


def pose_of(vehicle: Vehicle) -> Pose:
    body = vehicle.body
    return Pose(vehicle.time_s, body.east, body.north, body.alt, body.roll, body.pitch, body.yaw)


class LidarStream:
    """The LIDAR on one vehicle and the TCP server that carries its bytes."""

    def __init__(
        self,
        listen: ListenAddress,
        scene: Path | None,
        rate_hz: float,
        seed: int,
        wire: str = "ydlidar",
    ) -> None:
        self.listen = listen
        self.world: World = load_scene(scene) if scene is not None else default_scene()
        self._seed = seed
        self.lidar = Lidar(self.world, LidarSpec(rate_hz=rate_hz), seed=seed)
        self.address: ListenAddress | None = None
        self._server: asyncio.Server | None = None
        self._clients: set[asyncio.StreamWriter] = set()
        self.wire = wire_format(wire)
        # the clients that started a scan, and its mode (one encoder per mode in use)
        self._writers: dict[asyncio.StreamWriter, str] = {}
        self._encoders: dict[str, Encoder] = {}
        self._last_time = -1.0
        self.dropped_bytes = 0

    async def start(self) -> ListenAddress:
        self._server = await asyncio.start_server(
            self._on_client, self.listen.host, self.listen.port
        )
        port = int(self._server.sockets[0].getsockname()[1])
        self.address = ListenAddress("tcp", self.listen.host, port)
        log.info("LIDAR bytes on %s", self.address)
        return self.address

    async def stop(self) -> None:
        if self._server is not None:
            self._server.close()
        for writer in list(self._clients):
            writer.close()
        if self._server is not None:
            await self._server.wait_closed()
            self._server = None

    def restart(self) -> None:
        """The vehicle was rebooted: its clock starts again, and so does the head."""
        self.lidar = Lidar(self.world, self.lidar.spec, seed=self._seed)
        self._encoders.clear()
        self._last_time = -1.0

    def advance(self, vehicle: Vehicle) -> None:
        """Measure up to the vehicle's latest physics step and send the bytes."""
        if vehicle.time_s == self._last_time:
            return
        if vehicle.time_s < self._last_time:
            self.restart()
        self._last_time = vehicle.time_s
        beams = self.lidar.advance(pose_of(vehicle))
        if beams is None or not self._writers:
            return
        rate = self.lidar.spec.rate_hz
        encoded: dict[str, bytes] = {}
        for mode in set(self._writers.values()):
            encoder = self._encoders.get(mode)
            if encoder is None:
                encoder = self._encoders[mode] = self.wire.encoders[mode](self.lidar.spec.beams)
            encoded[mode] = encoder.encode(beams, rate)
        for writer, mode in list(self._writers.items()):
            data = encoded[mode]
            if not data or writer.transport.is_closing():
                continue
            if writer.transport.get_write_buffer_size() > MAX_PENDING_BYTES:
                self.dropped_bytes += len(data)
                continue
            writer.write(data)

    async def _on_client(self, reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
        commands = self.wire.commands()
        self._clients.add(writer)
        if self.wire.streams is not None:  # a sensor that sends unasked
            self._writers[writer] = self.wire.streams
        try:
            while data := await reader.read(4096):
                for action in commands.feed(data):
                    if isinstance(action, Start):
                        if self._writers.get(writer) != action.mode:
                            writer.write(action.reply)
                            self._writers[writer] = action.mode
                    elif isinstance(action, Stop):
                        self._writers.pop(writer, None)
                    elif isinstance(action, Reply):
                        writer.write(action.data)
        except (ConnectionError, OSError):
            pass
        finally:
            self._clients.discard(writer)
            self._writers.pop(writer, None)
            writer.close()
            with contextlib.suppress(ConnectionError, OSError):
                await writer.wait_closed()
