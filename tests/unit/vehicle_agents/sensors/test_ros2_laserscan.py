"""ROS 2 LaserScan as a scan source: the message's fields onto a turn (without ROS 2: the
message is built with the fields rclpy gives it), and the agent refusing a ROS 2 topic at
start-up where rclpy cannot be imported."""

from __future__ import annotations

import math
from types import SimpleNamespace

import pytest
from pydantic import ValidationError

from vehicle_agents.config import AgentSettings
from vehicle_agents.sensors.ros2 import rclpy_available, turn_from_laserscan


def _laserscan(stamp: float, ranges: list[float], time_increment: float) -> SimpleNamespace:
    sec = math.floor(stamp)
    return SimpleNamespace(
        header=SimpleNamespace(
            stamp=SimpleNamespace(sec=sec, nanosec=round((stamp - sec) * 1e9)), frame_id="laser"
        ),
        angle_min=-math.pi,
        angle_max=math.pi,
        angle_increment=2 * math.pi / len(ranges),
        time_increment=time_increment,
        scan_time=0.1,
        range_min=0.12,
        range_max=12.0,
        ranges=ranges,
        intensities=[],
    )


def test_a_laserscan_is_a_turn_with_its_bad_ranges_left_out() -> None:
    ranges = [1.5, math.nan, math.inf, -1.0, 0.05, 12.5, 11.999, 0.0]
    message = _laserscan(1_760_000_000.25, ranges, time_increment=0.1 / len(ranges))
    # it arrived 30 ms after its first beam: on the agent's monotonic clock, at 500.0
    turn = turn_from_laserscan(message, arrived=500.0, wall=1_760_000_000.28)
    assert list(turn.ranges) == [1500, 0, 0, 0, 0, 0, 11999, 0]
    assert turn.start == pytest.approx(499.97)
    assert turn.duration_s == pytest.approx(0.1)
    assert turn.angle_min == pytest.approx(-math.pi)
    assert turn.angle_increment == pytest.approx(math.pi / 4)  # counter-clockwise, REP 103
    assert turn.range_max_m == 12.0


def test_a_stamp_on_another_clock_is_placed_by_its_arrival() -> None:
    message = _laserscan(42.0, [2.0] * 4, time_increment=0.0)  # sim time; all at once
    turn = turn_from_laserscan(message, arrived=500.0, wall=1_760_000_000.0)
    assert turn.start == pytest.approx(500.0, abs=0.01)
    assert turn.duration_s < 0.01


@pytest.mark.skipif(rclpy_available(), reason="rclpy is installed here")
def test_a_ros2_topic_without_rclpy_is_refused_at_start_up() -> None:
    with pytest.raises(ValidationError, match="needs rclpy"):
        AgentSettings(lidar="ros2:/scan")
    assert AgentSettings(lidar="tcp://127.0.0.1:5770").lidar == "tcp://127.0.0.1:5770"
