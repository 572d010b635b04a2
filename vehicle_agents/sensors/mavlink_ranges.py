"""MAVLink OBSTACLE_DISTANCE and DISTANCE_SENSOR from the flight controller, for a
rangefinder wired to the autopilot (ArduPilot's proximity library reports 8 sectors as
DISTANCE_SENSOR, PX4 72 as OBSTACLE_DISTANCE; SITL can simulate either)."""

from __future__ import annotations

import asyncio
import math
from array import array
from collections.abc import AsyncIterator
from typing import Any

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from vehicle_agents.sensors.turn import SNAPSHOT_S, Turn


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
