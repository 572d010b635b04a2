"""Ranges from the flight controller as scans: ArduPilot's proximity sectors as a burst of
DISTANCE_SENSOR, PX4's OBSTACLE_DISTANCE (nose- or north-aligned), as real MAVLink bytes,
through the agent's relay and the hub's world points to where the obstacle is."""

from __future__ import annotations

import asyncio
import math
from typing import Any

import numpy as np
import pytest
from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from backend.scans.points import world_points
from common.geodesy import LocalFrame
from protocol.scans import decode_scan, encode_scan
from vehicle_agents.sensors.fcu_time import FcuClock, PoseHistory
from vehicle_agents.sensors.mavlink_ranges import MavlinkRangeSource
from vehicle_agents.sensors.relay import ScanOutbox, ScanRelay
from vehicle_agents.sensors.turn import Turn

SITE = LocalFrame(-35.363262, 149.165237, 584.0)
YAW = math.pi / 2  # the nose points east
BOOT_MS = 20_000


def _wire(message: Any) -> Any:
    """The message packed to bytes by one MAVLink end and parsed by another."""
    data = message.pack(mavlink2.MAVLink(None, srcSystem=1, srcComponent=1))
    parsed = mavlink2.MAVLink(None).parse_buffer(data)
    assert parsed is not None
    assert len(parsed) == 1
    return parsed[0]


def _distance_sensor(orientation: int, cm: int, at_ms: int = BOOT_MS) -> Any:
    # as ArduPilot's GCS_MAVLINK::send_proximity: ids from 10, 20 cm to 12 m, a laser
    return _wire(
        mavlink2.MAVLink_distance_sensor_message(
            at_ms,
            20,
            1200,
            cm,
            mavlink2.MAV_DISTANCE_SENSOR_LASER,
            10 + orientation,
            orientation,
            0,
        )
    )


def _obstacle_distance(frame: int, distances_cm: list[int], offset_deg: float = 0.0) -> Any:
    distances = distances_cm + [65535] * (72 - len(distances_cm))
    return _wire(
        mavlink2.MAVLink_obstacle_distance_message(
            BOOT_MS * 1000,
            mavlink2.MAV_DISTANCE_SENSOR_LASER,
            distances,
            0,
            20,
            1200,
            5.0,
            offset_deg,
            frame,
        )
    )


def _turns(source: MavlinkRangeSource) -> list[Turn]:
    turns = []
    queue = source._queue
    while not queue.empty():
        turns.append(queue.get_nowait())
    return turns


def test_a_proximity_burst_of_distance_sensor_is_one_eight_sector_turn() -> None:
    source = MavlinkRangeSource()
    source.on_message(_distance_sensor(mavlink2.MAV_SENSOR_ROTATION_PITCH_270, 250))  # down
    for orientation in range(8):
        # sector 2 (90 deg right) sees nothing: ArduPilot sends its maximum
        source.on_message(
            _distance_sensor(orientation, 1200 if orientation == 2 else 300 + orientation)
        )
    turns = _turns(source)
    assert len(turns) == 1
    turn = turns[0]
    assert list(turn.ranges) == [3000, 3010, 0, 3030, 3040, 3050, 3060, 3070]
    assert turn.angle_increment == pytest.approx(-math.radians(45.0))  # clockwise
    assert turn.fcu_start_s == pytest.approx(BOOT_MS / 1000)
    assert source.stats["not_horizontal"] == 1
    # A lone forward rangefinder: its reading ends the burst when the next instant comes.
    source.on_message(_distance_sensor(0, 500, BOOT_MS + 100))
    source.on_message(_distance_sensor(0, 510, BOOT_MS + 200))
    assert [list(t.ranges) for t in _turns(source)] == [[5000] + [0] * 7]


def test_obstacle_distance_leaves_distance_sensor_out() -> None:
    source = MavlinkRangeSource()
    source.on_message(_obstacle_distance(mavlink2.MAV_FRAME_BODY_FRD, [400]))
    for orientation in range(8):
        source.on_message(_distance_sensor(orientation, 300))
    turns = _turns(source)
    assert len(turns) == 1
    assert len(turns[0].ranges) == 72
    assert turns[0].ranges[0] == 4000
    assert sum(1 for r in turns[0].ranges if r) == 1  # UINT16_MAX is unknown, not a point


def _world(source: MavlinkRangeSource) -> np.ndarray:
    """The source's one turn, stamped by the relay with a pose facing east, as the hub's
    world points."""

    def message(kind: str, ms: int, **fields: float) -> Any:
        return type("M", (), {"get_type": lambda self: kind, "time_boot_ms": ms, **fields})()

    poses = PoseHistory(FcuClock(), monotonic=lambda: 100.0)
    for ms in (BOOT_MS - 100, BOOT_MS + 100):
        lat, lon = SITE.to_geo(0.0, 0.0)
        poses.on_message(
            message("GLOBAL_POSITION_INT", ms, lat=lat * 1e7, lon=lon * 1e7, alt=590_000)
        )
        poses.on_message(message("ATTITUDE", ms, roll=0.0, pitch=0.0, yaw=YAW))
    relay = ScanRelay(source, poses, ScanOutbox(10), monotonic=lambda: 100.0, wall=lambda: 1e9)
    [turn] = _turns(source)
    frame = asyncio.run(relay.stamp(turn))
    assert frame is not None
    return world_points(decode_scan(encode_scan(frame)), SITE).enu


def test_sectors_land_where_the_obstacles_are_in_the_nose_and_the_north_frames() -> None:
    ahead = MavlinkRangeSource()  # ArduPilot: sector 0 is the nose
    for orientation in range(8):
        ahead.on_message(_distance_sensor(orientation, 500 if orientation == 0 else 1200))
    assert _world(ahead)[:, :2] == pytest.approx(np.array([[5.0, 0.0]]), abs=0.02)  # east

    body = (
        MavlinkRangeSource()
    )  # PX4: 5 degree sectors from the nose, clockwise; max + 1 is no obstacle
    body.on_message(_obstacle_distance(mavlink2.MAV_FRAME_BODY_FRD, [1201] * 18 + [400]))
    assert _world(body)[:, :2] == pytest.approx(np.array([[0.0, -4.0]]), abs=0.02)  # 90 right

    north = MavlinkRangeSource()  # the default frame counts from north, whatever the yaw
    north.on_message(_obstacle_distance(mavlink2.MAV_FRAME_GLOBAL, [400]))
    assert _world(north)[:, :2] == pytest.approx(np.array([[0.0, 4.0]]), abs=0.02)
