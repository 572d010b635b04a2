"""Scan sources behind one interface: each yields whole turns, stamped on the agent's clock.

- `SerialLidarSource`: a Slamtec, YDLIDAR or LDROBOT LIDAR on a serial port
  (``/dev/ttyUSB0``), or the simulator's LIDAR socket (``tcp://HOST:PORT``), whose bytes
  are the same; parsed by `vehicle_agents.sensors.lidar` (the model picks the family).
- `MavlinkRangeSource`: MAVLink OBSTACLE_DISTANCE and DISTANCE_SENSOR from the flight
  controller, for a rangefinder wired to the autopilot (ArduPilot's proximity library
  reports 8 sectors as DISTANCE_SENSOR, PX4 72 as OBSTACLE_DISTANCE; SITL can simulate
  either).
- `vehicle_agents.sensors.ros2.LaserScanSource`: a ROS 2 ``sensor_msgs/LaserScan``
  topic, where rclpy is installed (a `Turn` maps one-to-one onto a LaserScan). rclpy is
  not a dependency of the agent and is imported only when that source starts.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import math
import threading
import time
from array import array
from collections import deque
from collections.abc import AsyncIterator, Callable
from dataclasses import dataclass, field
from typing import Any, Protocol

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from vehicle_agents.sensors.envelope import lower_envelope_slope
from vehicle_agents.sensors.lidar.common import Packet
from vehicle_agents.sensors.lidar.models import (
    DEFAULT_MODEL,
    make_parser,
    model_named,
    start_commands,
    stop_command,
)
from vehicle_agents.sensors.lidar.rplidar import motor_pwm

log = logging.getLogger(__name__)

READ_SIZE = 4096
DEFAULT_PERIOD_S = 0.1


@dataclass(frozen=True, slots=True)
class Turn:
    """One full turn of the head. Beam ``i`` points at ``angle_min + i * angle_increment``
    (radians, counter-clockwise from the sensor's forward axis) and was measured at
    ``start + i * duration_s / beams``. ``start`` is agent monotonic seconds, unless
    ``fcu_start_s`` gives the flight controller's own time for it (MAVLink sources).
    A ``north_aligned`` turn's angles count from north (the relay turns them into the
    sensor's frame with the vehicle's yaw)."""

    start: float
    duration_s: float
    angle_min: float
    angle_increment: float
    ranges: array[int]  # millimetres, 0 for no return
    range_max_m: float
    fcu_start_s: float | None = None
    north_aligned: bool = False  # angle_min counts from north, not the sensor's forward


SNAPSHOT_S = 1e-3  # a flight controller's ranges are one instant's, not a sweep's


class ScanSource(Protocol):
    """Where turns come from; `stats` counts what each source threw away."""

    stats: dict[str, int]

    def turns(self) -> AsyncIterator[Turn]: ...


CLOCK_WINDOW = 800  # packets: a few seconds of a T-mini Pro at 10 Hz
REFIT_EVERY = 50


class SensorClock:
    """When each beam was measured, on the agent's clock.

    The head samples at a steady rate, so beam number ``g`` (counted over all turns) was
    measured at ``origin + g * spacing``. Each packet, stamped on arrival, is a sample of
    that line, late by its trip (the UART, the OS, the event loop) but never early: the
    spacing is fitted through the samples of the last few seconds, and the line is lowered
    to the least delayed of them. One delayed read then moves nothing, and the start of a
    turn comes out to within the best trip time of the window, not of that one turn.
    """

    def __init__(self, spacing_s: float) -> None:
        self._samples: deque[tuple[int, float]] = deque(maxlen=CLOCK_WINDOW)
        self.reset(spacing_s)

    def reset(self, spacing_s: float) -> None:
        """Start again from the sensor's stated rate (before any turn was timed)."""
        self.spacing_s = spacing_s
        self._samples.clear()
        self._origin: float | None = None
        self._since_fit = 0

    def add(self, beam: int, arrived: float) -> None:
        self._samples.append((beam, arrived))
        self._since_fit += 1
        if self._origin is None or self._since_fit >= REFIT_EVERY:
            self._fit()
        else:
            self._origin = min(self._origin, arrived - beam * self.spacing_s)

    def _fit(self) -> None:
        self._since_fit = 0
        samples = list(self._samples)
        if len(samples) >= 20 and samples[-1][0] > samples[0][0]:
            self.spacing_s = lower_envelope_slope(samples, self.spacing_s)
        self._origin = min(t - g * self.spacing_s for g, t in samples)

    def time_of(self, beam: int) -> float:
        assert self._origin is not None
        return self._origin + beam * self.spacing_s


@dataclass
class TurnAssembler:
    """Packets into turns on a fixed grid of ``resolution_deg`` beams, each turn
    timed by a `SensorClock` (the sensor's own frequency only until it has samples)."""

    resolution_deg: float = 0.5
    range_max_m: float = 12.0
    _ranges: array[int] | None = None
    _turn: int = -1
    _beams: int = field(init=False)
    _clock: SensorClock = field(init=False)

    def __post_init__(self) -> None:
        self._beams = round(360.0 / self.resolution_deg)
        self._clock = SensorClock(DEFAULT_PERIOD_S / self._beams)

    def add(self, packet: Packet, arrived: float) -> Turn | None:
        done = None
        beams = self._beams
        if packet.zero:
            if self._ranges is not None:
                done = self._finish()
            elif packet.scan_hz:
                self._clock.reset(1.0 / (packet.scan_hz * beams))
            self._ranges = array("H", bytes(2 * beams))
            self._turn += 1
        ranges = self._ranges
        if ranges is None:  # the middle of a turn whose start was not seen
            return None
        step = self.resolution_deg
        top = round(self.range_max_m * 1000.0)
        for angle, distance in zip(packet.angles_deg, packet.distances_mm, strict=True):
            if 0 < distance <= top:
                ranges[round(angle / step) % beams] = distance
        last = packet.angles_deg[-1] / 360.0 * beams
        self._clock.add(round(self._turn * beams + last), arrived)
        return done

    def _finish(self) -> Turn:
        assert self._ranges is not None
        start = self._clock.time_of(self._turn * self._beams)
        end = self._clock.time_of((self._turn + 1) * self._beams)
        return Turn(
            start=start,
            duration_s=end - start,
            angle_min=0.0,
            angle_increment=-math.radians(self.resolution_deg),  # the head turns clockwise
            ranges=self._ranges,
            range_max_m=self.range_max_m,
        )


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


class MavlinkRangeSource:
    """Ranges the flight controller measured, from its MAVLink stream (an FcuLink listener
    feeds `on_message`); each message, or each burst of them, is one turn.

    - OBSTACLE_DISTANCE (PX4's collision prevention sends it, 72 sectors of 5 degrees;
      ArduPilot takes it in from companion computers): centimetres per sector,
      ``max_distance + 1`` for no obstacle, UINT16_MAX for unknown, 0 for touching.
      Sectors run clockwise from ``angle_offset``; in MAV_FRAME_BODY_FRD from the nose,
      in MAV_FRAME_GLOBAL or MAV_FRAME_LOCAL_NED (the default) from north.
    - DISTANCE_SENSOR: ArduPilot's proximity library sends its 8 horizontal sectors as a
      burst of 8 of these (orientations MAV_SENSOR_ROTATION_NONE to _YAW_315, 45 degrees
      apart clockwise), a plain rangefinder one. Readings at or beyond ``max_distance``
      are no return; up- and down-facing (pitched) sensors are not part of a 2-D scan and
      are counted, not used. A burst ends when all 8 directions came, or when a message
      of another instant or a direction already in it starts the next.

    Once OBSTACLE_DISTANCE has been seen, DISTANCE_SENSOR is left out: both describe the
    same surroundings, and OBSTACLE_DISTANCE is the finer one.
    """

    NO_READING = 65535
    SECTORS = 8  # MAV_SENSOR_ROTATION_NONE .. MAV_SENSOR_ROTATION_YAW_315
    FRAME_BODY_FRD = mavlink2.MAV_FRAME_BODY_FRD
    NORTH_FRAMES = frozenset({mavlink2.MAV_FRAME_GLOBAL, mavlink2.MAV_FRAME_LOCAL_NED})

    def __init__(self, queue_size: int = 4) -> None:
        self._queue: asyncio.Queue[Turn] = asyncio.Queue(maxsize=queue_size)
        self.stats: dict[str, int] = {
            "obstacle_distance": 0,
            "distance_sensor": 0,
            "not_horizontal": 0,
            "unknown_frame": 0,
            "dropped": 0,
        }
        self._obstacle_distance_seen = False
        self._burst: dict[int, tuple[int, int]] = {}  # orientation: (cm, max cm)
        self._burst_ms: int | None = None

    def on_message(self, message: Any) -> None:
        kind = message.get_type()
        if kind == "OBSTACLE_DISTANCE":
            self._obstacle_distance(message)
        elif kind == "DISTANCE_SENSOR" and not self._obstacle_distance_seen:
            self._distance_sensor(message)

    def _obstacle_distance(self, message: Any) -> None:
        self.stats["obstacle_distance"] += 1
        self._obstacle_distance_seen = True
        frame = int(getattr(message, "frame", 0))
        if frame != self.FRAME_BODY_FRD and frame not in self.NORTH_FRAMES:
            self.stats["unknown_frame"] += 1
            return
        increment = float(message.increment_f) or float(message.increment)
        if increment <= 0.0:
            return
        count = min(72, math.floor(360.0 / increment + 1e-6))
        max_cm = int(message.max_distance)
        ranges = array("H", bytes(2 * count))
        for i, cm in enumerate(message.distances[:count]):
            if cm <= max_cm and cm != self.NO_READING:
                ranges[i] = max(cm, 1) * 10  # 0 cm is touching, not "no return"
        self._put(
            Turn(
                start=0.0,
                duration_s=SNAPSHOT_S,
                angle_min=-math.radians(float(message.angle_offset)),
                angle_increment=-math.radians(increment),
                ranges=ranges,
                range_max_m=max_cm / 100.0,
                fcu_start_s=int(message.time_usec) / 1e6,
                north_aligned=frame in self.NORTH_FRAMES,
            )
        )

    def _distance_sensor(self, message: Any) -> None:
        self.stats["distance_sensor"] += 1
        orientation = int(message.orientation)
        if orientation >= self.SECTORS:  # pitched up or down, or a custom rotation
            self.stats["not_horizontal"] += 1
            return
        at_ms = int(message.time_boot_ms)
        if self._burst and (at_ms != self._burst_ms or orientation in self._burst):
            self._flush()
        self._burst_ms = at_ms
        self._burst[orientation] = (int(message.current_distance), int(message.max_distance))
        if len(self._burst) == self.SECTORS:
            self._flush()

    def _flush(self) -> None:
        burst, self._burst = self._burst, {}
        assert self._burst_ms is not None
        ranges = array("H", bytes(2 * self.SECTORS))
        for orientation, (cm, max_cm) in burst.items():
            if 0 < cm < max_cm:
                ranges[orientation] = cm * 10
        self._put(
            Turn(
                start=0.0,
                duration_s=SNAPSHOT_S,
                angle_min=0.0,
                angle_increment=-math.radians(360.0 / self.SECTORS),  # clockwise
                ranges=ranges,
                range_max_m=max(max_cm for _, max_cm in burst.values()) / 100.0,
                fcu_start_s=self._burst_ms / 1000.0,
            )
        )

    def _put(self, turn: Turn) -> None:
        if self._queue.full():  # newest wins
            self._queue.get_nowait()
            self.stats["dropped"] += 1
        self._queue.put_nowait(turn)

    async def turns(self) -> AsyncIterator[Turn]:
        while True:
            yield await self._queue.get()
