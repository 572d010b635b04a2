"""A Slamtec, YDLIDAR or LDROBOT LIDAR on a serial port (``/dev/ttyUSB0``), or the
simulator's LIDAR socket (``tcp://HOST:PORT``), whose bytes are the same; parsed by
`vehicle_agents.sensors.lidar` (the model picks the family)."""

from __future__ import annotations

import asyncio
import contextlib
import logging
import threading
import time
from collections.abc import AsyncIterator, Callable
from typing import Any

from vehicle_agents.sensors.lidar.models import (
    DEFAULT_MODEL,
    make_parser,
    model_named,
    start_commands,
    stop_command,
)
from vehicle_agents.sensors.lidar.rplidar import motor_pwm
from vehicle_agents.sensors.turn import Turn
from vehicle_agents.sensors.turn_assembly import TurnAssembler

log = logging.getLogger(__name__)

READ_SIZE = 4096

COMMAND_GAP_S = 0.05  # between commands on a serial line: a sensor answers one, then reads on


class SerialLidarSource:
    """A serial LIDAR on ``tcp://HOST:PORT`` (the simulator) or a serial device path. The
    same commands start it on either (stop whatever it was doing, ask its information and
    health, start the scan), and a health answer that is not good is logged. ``stats``:
    the parser's packets, points and drops by reason, refreshed with every turn."""

    def __init__(
        self,
        url: str,
        resolution_deg: float = 0.5,
        baud: int | None = None,
        model: str = DEFAULT_MODEL,
        scan_mode: int = 0,
        monotonic: Callable[[], float] = time.monotonic,
    ) -> None:
        self.url = url
        self.model = model_named(model)
        self.baud = baud or self.model.baud
        self.scan_mode = scan_mode
        self.parser = make_parser(self.model)
        self.assembler = TurnAssembler(resolution_deg)
        self._monotonic = monotonic
        self.stats: dict[str, int] = {}

    async def turns(self) -> AsyncIterator[Turn]:
        reported = None
        async for chunk, arrived in self._chunks():
            packets = self.parser.feed(chunk)
            self.stats = self.parser.stats.as_dict()
            if self.parser.health != reported:
                reported = self.parser.health
                if reported is not None and reported.status != 0:
                    log.warning("LIDAR %s reports %s", self.url, reported.text)
            for packet in packets:
                turn = self.assembler.add(packet, arrived)
                if turn is not None:
                    yield turn

    async def _chunks(self) -> AsyncIterator[tuple[bytes, float]]:
        stop = stop_command(self.model)
        if self.url.startswith("tcp://"):
            host, _, port = self.url.removeprefix("tcp://").rpartition(":")
            reader, writer = await asyncio.open_connection(host, int(port))
            try:
                writer.write(stop + b"".join(start_commands(self.model, self.scan_mode)))
                await writer.drain()
                while data := await reader.read(READ_SIZE):
                    yield data, self._monotonic()
            finally:
                with contextlib.suppress(ConnectionError, OSError):
                    writer.write(stop)
                writer.close()
                with contextlib.suppress(ConnectionError, OSError):
                    await writer.wait_closed()
            raise ConnectionError(f"LIDAR {self.url} closed the connection")
        async for item in self._serial_chunks(stop):
            yield item

    def _open_serial(self, stop: bytes) -> Any:
        """Open the port and start the sensor (blocking: run in a thread)."""
        import serial  # type: ignore[import-untyped]  # pyserial: in the agent's base set

        port = serial.Serial(self.url, self.baud, timeout=0.05)
        if self.model.family == "rplidar":
            # Slamtec's USB adapter runs the motor while DTR is low (a bare UART has no
            # DTR line: the motor is then wired to run)
            with contextlib.suppress(OSError):
                port.dtr = False
        if stop:
            port.write(stop)
            time.sleep(COMMAND_GAP_S)
        port.reset_input_buffer()  # the packets of a scan left running
        for command in start_commands(self.model, self.scan_mode):
            port.write(command)
            time.sleep(COMMAND_GAP_S)
        return port

    async def _serial_chunks(self, stop_bytes: bytes) -> AsyncIterator[tuple[bytes, float]]:
        """A serial port, read by a thread (pyserial blocks) into the event loop."""
        import serial

        port = await asyncio.to_thread(self._open_serial, stop_bytes)
        queue: asyncio.Queue[tuple[bytes, float]] = asyncio.Queue(maxsize=256)
        loop = asyncio.get_running_loop()
        stop = threading.Event()

        def put(item: tuple[bytes, float]) -> None:
            if queue.full():  # the loop fell behind: drop bytes, as a UART would
                self.parser.stats.drops["queue_full_bytes"] += len(item[0])
                return
            queue.put_nowait(item)

        def read() -> None:
            while not stop.is_set():
                data = port.read(READ_SIZE)
                if data:
                    loop.call_soon_threadsafe(put, (bytes(data), self._monotonic()))

        reader = threading.Thread(target=read, name="lidar-serial", daemon=True)
        reader.start()
        try:
            while True:
                yield await queue.get()
        finally:
            stop.set()
            await asyncio.to_thread(reader.join, 1.0)
            with contextlib.suppress(OSError, serial.SerialException):
                port.write(stop_bytes)  # the scan stops
                if self.model.motor_pwm:
                    port.write(motor_pwm(0))  # an A2/A3's motor stops
                if self.model.family == "rplidar":
                    port.dtr = True  # and an A1's (or any on Slamtec's USB adapter)
            port.close()
