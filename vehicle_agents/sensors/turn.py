"""A whole turn of a scanning sensor, and the interface every scan source offers.

The sources: `vehicle_agents.sensors.serial_lidar.SerialLidarSource` (a Slamtec, YDLIDAR
or LDROBOT LIDAR on a serial port, or the simulator's LIDAR socket),
`vehicle_agents.sensors.mavlink_ranges.MavlinkRangeSource` (the flight controller's
OBSTACLE_DISTANCE and DISTANCE_SENSOR) and `vehicle_agents.sensors.ros2.LaserScanSource`
(a ROS 2 ``sensor_msgs/LaserScan`` topic, where rclpy is installed). Each yields whole
turns, stamped on the agent's clock.
"""

from __future__ import annotations

from array import array
from collections.abc import AsyncIterator
from dataclasses import dataclass
from typing import Protocol


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
