"""World points of a scan (the sensor's mount, the body's attitude, a pose per beam) and
the bounded point map with its obstacles."""

from __future__ import annotations

import math
from array import array

import numpy as np
import pytest

from backend.scans.obstacles import ObstacleTracker, describe
from backend.scans.pointmap import MapObstacle, PointMap
from backend.scans.points import world_points
from common.geodesy import LocalFrame
from protocol.scans import Mount, ScanFrame, ScanPose

SITE = LocalFrame(-35.363262, 149.165237, 584.0)


def _frame(ranges_mm: list[int], start: ScanPose, end: ScanPose, mount: Mount) -> ScanFrame:
    return ScanFrame(
        seq=0,
        sensor_time_us=0,
        utc_time=1.0,
        duration_s=0.1,
        angle_min=0.0,
        angle_increment=-2 * math.pi / len(ranges_mm),
        range_max_m=12.0,
        pose_start=start,
        pose_end=end,
        ranges=array("H", ranges_mm),
        mount=mount,
    )


def test_the_mount_turns_and_offsets_the_sensor_on_the_body() -> None:
    here = ScanPose(SITE.origin.lat, SITE.origin.lon, 586.0)  # 2 m up, facing north
    # The sensor faces the body's right (yaw +90 deg), 10 cm ahead of the centre.
    mount = Mount(forward=0.1, yaw=math.pi / 2)
    points = world_points(_frame([5000, 0, 0, 0], here, here, mount), SITE).enu
    assert points == pytest.approx(np.array([[5.0, 0.1, 2.0]]), abs=1e-4)


def test_each_beam_gets_the_pose_of_its_instant() -> None:
    # Turning from north to east during the turn: beam 0 (ahead) at the start's heading,
    # beam 2 (behind, half-way) at 45 degrees.
    start = ScanPose(SITE.origin.lat, SITE.origin.lon, 584.0, yaw=0.0)
    end = ScanPose(SITE.origin.lat, SITE.origin.lon, 584.0, yaw=math.pi / 2)
    points = world_points(_frame([4000, 0, 4000, 0], start, end, Mount()), SITE).enu
    assert points[0] == pytest.approx([0.0, 4.0, 0.0], abs=1e-4)
    half = 4.0 / math.sqrt(2.0)
    assert points[1] == pytest.approx([-half, -half, 0.0], abs=1e-4)


def test_the_point_map_keeps_one_point_a_voxel_and_forgets_the_oldest() -> None:
    point_map = PointMap(voxel_m=0.1, max_voxels=1000)
    wall = np.column_stack([np.linspace(0, 5, 2000), np.full(2000, 3.0), np.full(2000, 1.0)])
    for _ in range(10):  # the same wall seen again and again
        point_map.add(wall, 0.0)
    assert len(point_map) == 51  # 0 to 5 m inclusive, 10 cm apart
    row = (np.arange(2000) + 0.5) * 0.1  # voxel centres: 2,000 distinct voxels
    point_map.add(np.column_stack([row, np.zeros(2000), np.ones(2000)]), 1.0)
    assert len(point_map) == 1000
    assert point_map.evicted == 1051


def test_obstacles_are_clusters_above_the_ground_with_their_extents() -> None:
    point_map = PointMap(voxel_m=0.1)
    angles = np.linspace(0, 2 * math.pi, 400)
    post = np.column_stack([3 + 0.4 * np.cos(angles), 2 + 0.4 * np.sin(angles), np.ones(400)])
    ground = np.column_stack([np.linspace(-5, 5, 100), np.zeros(100), np.zeros(100)])
    point_map.add(np.vstack([post, ground]), 0.0)
    (found,) = point_map.obstacles()
    assert found.east_min == pytest.approx(2.6, abs=0.11)  # to the voxel
    assert found.east_max == pytest.approx(3.4, abs=0.11)
    assert found.north_min == pytest.approx(1.6, abs=0.11)


def _obstacle(east: float, north: float, size: float = 1.0) -> MapObstacle:
    return MapObstacle(0, east, east + size, north, north + size, 0.0, 2.0, 10)


def test_obstacles_keep_their_ids_while_seen_and_their_coming_and_going_are_told() -> None:
    tracker = ObstacleTracker()
    first = tracker.update([_obstacle(0, 0), _obstacle(10, 0)])
    assert [o.id for o in first.appeared] == [1, 2]
    assert not first.gone
    # the first grew as more of it was seen, the second left the map, a third came
    second = tracker.update([_obstacle(20, 0), _obstacle(-0.5, -0.5, size=2.0)])
    assert [(o.id, o.east_min) for o in second.current] == [(3, 20), (1, -0.5)]
    assert [o.id for o in second.appeared] == [3]
    assert [o.id for o in second.gone] == [2]
    assert not tracker.update([_obstacle(20.2, 0), _obstacle(0, 0)]).appeared
    assert "obstacle 3 found: 1.0 m x 1.0 m, up to 2.0 m, centred 20.5 m east" in describe(
        second.appeared[0], "found"
    )
