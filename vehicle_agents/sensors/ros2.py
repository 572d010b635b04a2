"""ROS 2 ``sensor_msgs/LaserScan`` as a scan source (``--lidar ros2:/scan``), for a drone
whose LIDAR already has a ROS 2 driver (ydlidar_ros2_driver, rplidar_ros, a simulator).

rclpy is optional: ROS 2 installs from its own distribution (apt packages or a workspace
that is sourced), not from PyPI, so it is no dependency of the agent and is imported
only when this source starts. The agent refuses ``--lidar ros2:...`` at start-up when
rclpy cannot be imported (vehicle_agents/config.py).

A LaserScan maps onto a `Turn` one to one: both count angles counter-clockwise from the
sensor's forward axis (REP 103), and the header's stamp is the first beam's time. The
stamp is on the ROS clock (the system's wall clock unless ``use_sim_time``), so it is
carried to the agent's monotonic clock through the difference of the two at arrival.
Ranges that are NaN, infinite or outside ``[range_min, range_max]`` are no return.
"""

from __future__ import annotations

import asyncio
import importlib
import math
import threading
import time
from array import array
from collections.abc import AsyncIterator, Callable
from typing import Any

from vehicle_agents.sensors.turn import SNAPSHOT_S, Turn

SCHEME = "ros2:"
MAX_RANGE_MM = 65535
STAMP_TRUST_S = 5.0  # a stamp further from the wall clock than this is another clock's


def rclpy_available() -> bool:
    try:
        importlib.import_module("rclpy")
    except ImportError:
        return False
    return True


def turn_from_laserscan(message: Any, arrived: float, wall: float) -> Turn:
    """One LaserScan as a turn. ``arrived`` is the agent's monotonic clock and ``wall`` the
    wall clock, both read when the message came."""
    ranges_m = list(message.ranges)
    low, high = float(message.range_min), float(message.range_max)
    ranges = array("H", bytes(2 * len(ranges_m)))
    for i, r in enumerate(ranges_m):
        if math.isfinite(r) and low <= r <= high and r > 0.0:
            ranges[i] = min(MAX_RANGE_MM, round(r * 1000.0))
    increment = float(message.time_increment)
    duration = increment * len(ranges_m) if increment > 0.0 else SNAPSHOT_S
    stamp = message.header.stamp.sec + message.header.stamp.nanosec / 1e9
    age = wall - stamp
    if not 0.0 <= age <= STAMP_TRUST_S:  # sim time, or an unset stamp: the arrival tells
        age = duration
    return Turn(
        start=arrived - age,
        duration_s=duration,
        angle_min=float(message.angle_min),
        angle_increment=float(message.angle_increment),
        ranges=ranges,
        range_max_m=min(high, MAX_RANGE_MM / 1000.0),
    )


class LaserScanSource:
    """Subscribes to a LaserScan topic in its own rclpy context, spun by a thread; the
    newest turns wait in a small queue (the oldest is dropped and counted)."""

    def __init__(
        self,
        url: str,
        queue_size: int = 4,
        monotonic: Callable[[], float] = time.monotonic,
        wall: Callable[[], float] = time.time,
    ) -> None:
        self.topic = url.removeprefix(SCHEME) or "/scan"
        self._queue_size = queue_size
        self._monotonic = monotonic
        self._wall = wall
        self.stats: dict[str, int] = {"messages": 0, "dropped": 0}

    def _put(self, queue: asyncio.Queue[Turn], turn: Turn) -> None:
        if queue.full():
            queue.get_nowait()
            self.stats["dropped"] += 1
        queue.put_nowait(turn)

    async def turns(self) -> AsyncIterator[Turn]:  # pragma: no cover - needs ROS 2
        rclpy = importlib.import_module("rclpy")
        executors = importlib.import_module("rclpy.executors")
        qos = importlib.import_module("rclpy.qos")
        laser_scan = importlib.import_module("sensor_msgs.msg").LaserScan
        loop = asyncio.get_running_loop()
        queue: asyncio.Queue[Turn] = asyncio.Queue(self._queue_size)

        def on_scan(message: Any) -> None:  # on the spinning thread
            self.stats["messages"] += 1
            turn = turn_from_laserscan(message, self._monotonic(), self._wall())
            loop.call_soon_threadsafe(self._put, queue, turn)

        context = rclpy.Context()
        rclpy.init(context=context)
        node = rclpy.create_node("gcs_agent_lidar", context=context)
        node.create_subscription(laser_scan, self.topic, on_scan, qos.qos_profile_sensor_data)
        executor = executors.SingleThreadedExecutor(context=context)
        executor.add_node(node)
        spinner = threading.Thread(target=executor.spin, name="ros2-lidar", daemon=True)
        spinner.start()
        try:
            while True:
                yield await queue.get()
        finally:
            executor.shutdown()
            node.destroy_node()
            rclpy.shutdown(context=context)
            await asyncio.to_thread(spinner.join, 1.0)
