"""The simulated LIDAR's serial line, served over TCP: every client gets the sensor's bytes.

A real T-mini Pro is a serial port; here the same bytes go to whoever connects (the
agent's driver reads ``tcp://HOST:PORT`` as it reads ``/dev/ttyUSB0``). Like the sensor, a
connection idles until it sends the start command, and answers the stop and health
commands (simulator/ydlidar_wire.py), so the driver's start-up is exercised too. A client that falls
behind loses bytes, as a serial port's receive buffer would overflow, never the
simulator's memory; the parser resynchronises on the next packet header.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
from pathlib import Path

from simulator.config import ListenAddress
from simulator.lidar import Lidar, LidarSpec, Pose
from simulator.vehicle import Vehicle
from simulator.world import World, default_scene, load_scene
from simulator.ydlidar_wire import (
    COMMAND,
    GET_HEALTH,
    SCAN_RESPONSE,
    START_SCAN,
    STOP_SCAN,
    encode_beams,
    health,
)

log = logging.getLogger(__name__)

MAX_PENDING_BYTES = 64 * 1024  # about 2 s of a T-mini Pro's output


def pose_of(vehicle: Vehicle) -> Pose:
    body = vehicle.body
    return Pose(vehicle.time_s, body.east, body.north, body.alt, body.roll, body.pitch, body.yaw)


class LidarStream:
    """The LIDAR on one vehicle and the TCP server that carries its bytes."""

    def __init__(
        self, listen: ListenAddress, scene: Path | None, rate_hz: float, seed: int
    ) -> None:
        self.listen = listen
        self.world: World = load_scene(scene) if scene is not None else default_scene()
        self._seed = seed
        self.lidar = Lidar(self.world, LidarSpec(rate_hz=rate_hz), seed=seed)
        self.address: ListenAddress | None = None
        self._server: asyncio.Server | None = None
        self._clients: set[asyncio.StreamWriter] = set()
        self._writers: set[asyncio.StreamWriter] = set()  # the clients that started the scan
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
        data = encode_beams(beams, self.lidar.spec.rate_hz)
        for writer in list(self._writers):
            if writer.transport.is_closing():
                continue
            if writer.transport.get_write_buffer_size() > MAX_PENDING_BYTES:
                self.dropped_bytes += len(data)
                continue
            writer.write(data)

    def _command(self, command: int, writer: asyncio.StreamWriter) -> None:
        if command == START_SCAN:
            if writer not in self._writers:
                writer.write(SCAN_RESPONSE)
                self._writers.add(writer)
        elif command == STOP_SCAN:
            self._writers.discard(writer)
        elif command == GET_HEALTH:
            writer.write(health())

    async def _on_client(self, reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
        pending = b""
        self._clients.add(writer)
        try:
            while data := await reader.read(4096):
                pending += data
                while len(pending) >= 2:
                    if pending[0] != COMMAND:  # not a command's start: the sensor ignores it
                        pending = pending[1:]
                        continue
                    self._command(pending[1], writer)
                    pending = pending[2:]
        except (ConnectionError, OSError):
            pass
        finally:
            self._clients.discard(writer)
            self._writers.discard(writer)
            writer.close()
            with contextlib.suppress(ConnectionError, OSError):
                await writer.wait_closed()
