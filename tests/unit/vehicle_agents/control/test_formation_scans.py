"""Shared sensing: the leader's LIDAR scans reach a follower (as the hub relays them) and
the follower holds short of what they show.

Real frames all the way: a scan is encoded to its wire bytes and decoded as the hub does,
its returns placed in the world (backend.scans.points), thinned onto the formation's
plane (the relay's `in_frame`), sent as a `LeaderScan` JSON frame and decoded by the
agent's adapter, then taken into the follower's map."""

from __future__ import annotations

import math
from array import array

import pytest

from backend.scans.points import in_frame, world_points
from common.formation import LeaderState, Offset
from common.geodesy import LocalFrame
from protocol.messages import LeaderScan, encode, hub_to_agent
from protocol.scans import ScanFrame, ScanPose, decode_scan, encode_scan
from vehicle_agents.control.formation_follower import Follower
from vehicle_agents.control.formation_obstacles import ScanObstacles
from vehicle_agents.control.formation_setpoint import Action

HOME = LocalFrame(-35.363262, 149.165237, 584.0)  # the site and the formation's origin
BEAMS = 720
WALL_AHEAD_M = 6.0


def _wall_scan(leader_north: float) -> bytes:
    """A 720-beam turn from the leader at ``leader_north`` m, 8 m up, facing north: a wall
    straight ahead, seen by the beams within 10 degrees of forward (no return elsewhere)."""
    ranges = array("H", bytes(2 * BEAMS))
    increment = -2 * math.pi / BEAMS  # clockwise, as a YDLIDAR head turns
    for i in range(BEAMS):
        bearing = -i * increment  # clockwise from forward
        bearing = (bearing + math.pi) % (2 * math.pi) - math.pi
        if abs(bearing) <= math.radians(10):
            ranges[i] = round(WALL_AHEAD_M / math.cos(bearing) * 1000)
    lat, lon = HOME.to_geo(0.0, leader_north)
    pose = ScanPose(lat, lon, HOME.origin.alt + 8.0)
    frame = ScanFrame(
        seq=7,
        sensor_time_us=1_000_000,
        utc_time=1.7e9,
        duration_s=0.1,
        angle_min=0.0,
        angle_increment=increment,
        range_max_m=12.0,
        pose_start=pose,
        pose_end=pose,
        ranges=ranges,
    )
    return encode_scan(frame)


def _relayed(data: bytes) -> LeaderScan:
    """What a follower's agent receives for this scan."""
    frame = decode_scan(data)
    north, east = in_frame(world_points(frame, HOME), HOME, HOME, 0.2, 1024)
    sent = LeaderScan(
        formation_id="formation-1", time=frame.utc_time, seq=frame.seq, north=north, east=east
    )
    received = hub_to_agent.decode(encode(sent))
    assert isinstance(received, LeaderScan)
    return received


def test_the_leaders_scan_reaches_a_follower_on_the_formations_plane() -> None:
    scan = _relayed(_wall_scan(leader_north=10.0))
    assert scan.seq == 7
    assert 15 <= len(scan.north) <= 1024  # thinned to a point per 0.2 m cell
    # the wall: 6 m ahead of the leader, about 2 m wide
    assert all(15.9 <= n <= 16.2 for n in scan.north)
    assert min(scan.east) == pytest.approx(-1.06, abs=0.1)
    assert max(scan.east) == pytest.approx(1.06, abs=0.1)
    obstacles = ScanObstacles()
    obstacles.add(scan.north, scan.east, scan.seq)
    hit = obstacles.nearest(15.0, 0.5, 2.0)
    assert hit is not None
    assert hit[0] == pytest.approx(1.0, abs=0.1)
    assert obstacles.nearest(10.0, 0.5, 2.0) is None


def test_a_follower_holds_short_of_an_obstacle_the_leader_saw() -> None:
    """The slot is 5 m ahead of the leader: as the leader nears the wall it saw, the slot
    reaches the wall's 2 m clearance and the follower holds at the last clear target."""
    follower = Follower(HOME, Offset(5.0, 0.5, -6.0), min_separation_m=2.0)
    follower.clearance_m = 2.0
    scan = _relayed(_wall_scan(leader_north=6.0))
    follower.obstacles.add(scan.north, scan.east, scan.seq)

    follower.on_leader(LeaderState(4.0, 0.0, 8.0, 1.5, 0.0, 0.0, 0.0, time_s=0.0))
    clear = follower.tick(0.0, own=(9.0, 0.5, 2.0))  # its slot 3 m short of the wall
    assert clear.action is Action.TRACK
    assert clear.position == pytest.approx((9.0, 0.5, 2.0))

    follower.on_leader(LeaderState(6.0, 0.0, 8.0, 1.5, 0.0, 0.0, 0.0, time_s=1.3))
    held = follower.tick(1.3, own=(10.5, 0.5, 2.0))  # its slot 1 m short of it
    assert held.action is Action.HOLD_OBSTACLE
    assert held.position == pytest.approx((9.0, 0.5, 2.0))  # the last clear target
    assert held.velocity == (0.0, 0.0, 0.0)
    assert "1.0 m from an obstacle the leader saw at 12.0 m north" in held.reason
    assert "within the 2 m clearance" in held.reason

    # the leader turns east, away from the wall: the slot is clear again and tracked
    follower.on_leader(LeaderState(6.0, 0.0, 8.0, 0.0, 0.0, 0.0, math.pi / 2, time_s=2.0))
    assert follower.tick(2.0, own=(10.5, 0.5, 2.0)).action is Action.TRACK


def test_without_a_clearance_or_scans_nothing_is_held() -> None:
    follower = Follower(HOME, Offset(5.0, 0.5, -6.0), min_separation_m=2.0)
    scan = _relayed(_wall_scan(leader_north=6.0))
    follower.obstacles.add(scan.north, scan.east, scan.seq)
    follower.on_leader(LeaderState(6.0, 0.0, 8.0, 1.5, 0.0, 0.0, 0.0, time_s=0.0))
    assert follower.tick(0.0, own=(10.5, 0.5, 2.0)).action is Action.TRACK  # clearance 0
    follower = Follower(HOME, Offset(5.0, 0.5, -6.0), min_separation_m=2.0)
    follower.clearance_m = 2.0
    follower.on_leader(LeaderState(6.0, 0.0, 8.0, 1.5, 0.0, 0.0, 0.0, time_s=0.0))
    assert follower.tick(0.0, own=(10.5, 0.5, 2.0)).action is Action.TRACK  # no scans


def test_the_followers_map_is_bounded_and_keeps_the_newest() -> None:
    obstacles = ScanObstacles(cell_m=0.2, max_cells=100)
    obstacles.add([float(i) for i in range(150)], [0.0] * 150)
    assert len(obstacles) == 100
    assert obstacles.nearest(0.0, 0.0, 0.5) is None  # the oldest cells went first
    assert obstacles.nearest(149.0, 0.0, 0.5) is not None


def test_a_scan_with_unpaired_points_is_refused() -> None:
    with pytest.raises(ValueError, match="same number of points"):
        LeaderScan(formation_id="f", time=1.0, seq=1, north=[1.0, 2.0], east=[1.0])


def test_returns_from_the_ground_are_not_relayed_as_obstacles() -> None:
    """The leader 3 m up, nose down 20 degrees (accelerating): its forward beams reach the
    ground 8.2 m ahead. The relay leaves those out above the leader's home height."""
    ranges = array("H", bytes(2 * BEAMS))
    ranges[0] = round(3.0 / math.sin(math.radians(20)) * 1000)  # straight ahead
    ranges[BEAMS // 4] = 4000  # 90 degrees right, level with the sensor: a wall
    pose = ScanPose(HOME.origin.lat, HOME.origin.lon, HOME.origin.alt + 3.0, pitch=-0.349066)
    frame = decode_scan(
        encode_scan(
            ScanFrame(
                seq=1,
                sensor_time_us=0,
                utc_time=1.7e9,
                duration_s=0.1,
                angle_min=0.0,
                angle_increment=-2 * math.pi / BEAMS,
                range_max_m=12.0,
                pose_start=pose,
                pose_end=pose,
                ranges=ranges,
            )
        )
    )
    points = world_points(frame, HOME)
    everything = in_frame(points, HOME, HOME, 0.2, 1024)
    assert len(everything[0]) == 2
    north, east = in_frame(points, HOME, HOME, 0.2, 1024, above_msl=HOME.origin.alt + 0.3)
    assert north == pytest.approx([0.0], abs=0.05)  # the wall, to the right
    assert east == pytest.approx([4.0], abs=0.05)
