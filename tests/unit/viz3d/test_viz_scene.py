"""The fleet in the 3D scene, driven and read through the viser server's own API."""

from __future__ import annotations

import math

import numpy as np
import pytest

from backend.viz3d.colours import rgb, vehicle_colour
from backend.viz3d.frame import SceneFrame, attitude_wxyz, reframe
from backend.viz3d.scene import SCANS, FleetScene
from backend.viz3d.server import VizServer
from common.geodesy import LocalFrame
from protocol.messages import MissionItem
from tests.support.scenes import HOME, _node, _summary
from tests.viz_wire import scene_messages, scene_socket


@pytest.fixture
def scene(viz: VizServer) -> FleetScene:
    return FleetScene(viz.viser, SceneFrame(), trail_s=30.0)


def test_vehicles_appear_in_the_local_frame_move_and_leave_trails(
    viz: VizServer, scene: FleetScene
) -> None:
    truth = LocalFrame(*HOME)
    north_of_home = (47.398642, 8.545594, 498.0)  # ~100 m north, 10 m up
    scene.apply([_summary("alpha", 1.0, lat=HOME[0], lon=HOME[1], alt_msl=HOME[2] + 10)])
    scene.apply([_summary("alpha", 2.0, lat=north_of_home[0], lon=north_of_home[1], alt_msl=498.0)])
    frame = _node(viz.viser, "/vehicles/alpha")
    assert frame is not None
    np.testing.assert_allclose(frame.position, truth.to_enu(*north_of_home), atol=1e-3)
    assert abs(frame.position[1] - 100.1) < 0.5  # north
    trail = _node(viz.viser, "/trails/alpha")
    assert trail is not None
    np.testing.assert_allclose(trail.points[0][0], truth.to_enu(HOME[0], HOME[1], 498.0), atol=1e-2)
    np.testing.assert_allclose(trail.points[-1][1], frame.position, atol=1e-2)
    assert tuple(np.asarray(trail.colors).reshape(-1, 3)[0]) == rgb(vehicle_colour("alpha"))
    home = _node(viz.viser, "/homes/alpha")
    np.testing.assert_allclose(home.position, (0, 0, 0), atol=1e-6)  # the origin is home
    assert {"grid", "vehicles", "trails", "homes"} <= set(scene.layers_shown)


def test_a_trail_keeps_only_its_last_seconds(viz: VizServer, scene: FleetScene) -> None:
    for second in range(60):
        lat = HOME[0] + second * 1e-5  # ~1.1 m a second
        scene.apply([_summary("alpha", float(second), lat=lat, lon=HOME[1], alt_msl=500.0)])
    kept = scene.trail_points("alpha")
    # 30 s of trail at ~1.1 m/s: the first 29 points are gone.
    assert 30 <= len(kept) <= 32
    assert kept[0][1] > 29 * 1.0


def test_no_position_is_not_drawn_at_the_origin_and_bad_ones_are_counted(
    viz: VizServer, scene: FleetScene
) -> None:
    scene.apply(
        [
            _summary("nofix", 1.0),  # no position yet
            _summary("nan", 1.0, lat=math.nan, lon=HOME[1], alt_msl=500.0),
            _summary("far", 1.0, lat=-47.0, lon=HOME[1], alt_msl=500.0),
            _summary("high", 1.0, lat=HOME[0], lon=HOME[1], alt_msl=1e7),
        ]
    )
    for vehicle in ("nofix", "nan", "far", "high"):
        assert _node(viz.viser, f"/vehicles/{vehicle}") is None, vehicle
    assert scene.frame.skipped == {
        "not a number": 1,
        "too far from the origin": 1,
        "out of range": 1,
    }


def test_attitude_points_the_model_where_the_vehicle_heads() -> None:
    def nose(wxyz: np.ndarray) -> np.ndarray:
        w, x, y, z = wxyz
        # The body's forward axis (1, 0, 0), rotated by the quaternion.
        return np.array([1 - 2 * (y * y + z * z), 2 * (x * y + w * z), 2 * (x * z - w * y)])

    np.testing.assert_allclose(nose(attitude_wxyz(0, 0, 0)), (0, 1, 0), atol=1e-9)  # north
    np.testing.assert_allclose(nose(attitude_wxyz(0, 0, 90)), (1, 0, 0), atol=1e-9)  # east
    up = nose(attitude_wxyz(0, 30, 90))  # nose up 30° heading east
    np.testing.assert_allclose(
        up, (math.cos(math.radians(30)), 0, math.sin(math.radians(30))), atol=1e-9
    )
    w, x, y, z = attitude_wxyz(20, 0, 0)  # right wing down, heading north
    right = np.array([1 - 2 * (y * y + z * z), 2 * (x * y + w * z), 2 * (x * z - w * y)])
    left_axis = np.array([2 * (x * y - w * z), 1 - 2 * (x * x + z * z), 2 * (y * z + w * x)])
    assert right[1] > 0.99  # still north
    assert left_axis[2] > 0  # the left wing rose
    assert left_axis[0] < 0  # and points west


def test_the_mission_path_and_the_next_waypoint(viz: VizServer, scene: FleetScene) -> None:
    scene.apply([_summary("alpha", 1.0, lat=HOME[0], lon=HOME[1], alt_msl=HOME[2])])
    items = [
        MissionItem(command=22, lat=0, lon=0, alt=20),  # take-off: no position of its own
        MissionItem(command=16, lat=HOME[0] + 0.0009, lon=HOME[1], alt=20),
        MissionItem(command=16, lat=HOME[0] + 0.0009, lon=HOME[1] + 0.0013, alt=30),
    ]
    scene.show_mission("alpha", items, home_alt=HOME[2])
    path = scene.mission_path("alpha")
    assert len(path) == 2
    assert abs(path[0][2] - 20) < 0.01  # above home
    assert abs(path[1][0] - 97.9) < 1.0  # east
    assert _node(viz.viser, "/missions/alpha/path") is not None
    scene.apply(
        [_summary("alpha", 2.0, lat=HOME[0], lon=HOME[1], alt_msl=HOME[2], mission_current=2)]
    )
    np.testing.assert_allclose(
        _node(viz.viser, "/missions/alpha/next").position, path[1], atol=1e-3
    )
    scene.show_mission("alpha", [], home_alt=HOME[2])
    assert _node(viz.viser, "/missions/alpha/path") is None


def test_points_hook_places_points_as_given_and_shows_its_layer(
    viz: VizServer, scene: FleetScene
) -> None:
    assert "scans" not in scene.layers_shown  # no data, no layer
    points = np.array([[1.0, 2.0, 3.0], [np.nan, 0, 0], [-4.0, 5.0, 0.5]])
    scene.show_points(SCANS, "alpha", points, colour=(255, 0, 0))
    cloud = _node(viz.viser, "/scans/alpha")
    np.testing.assert_allclose(cloud.points, [[1, 2, 3], [-4, 5, 0.5]], atol=1e-2)  # float16
    assert "scans" in scene.layers_shown


def test_a_browser_joining_mid_flight_gets_the_current_scene_at_once(
    viz: VizServer, scene: FleetScene
) -> None:
    for second in range(5):
        lat = HOME[0] + second * 1e-4
        scene.apply([_summary("alpha", float(second), lat=lat, lon=HOME[1], alt_msl=500.0)])
    latest = _node(viz.viser, "/vehicles/alpha").position
    with scene_socket(viz) as ws:
        messages = scene_messages(ws.recv(timeout=10))  # type: ignore[arg-type]
    names = {message.get("name") for message in messages}
    assert {"/vehicles/alpha", "/vehicles/alpha/body", "/trails/alpha"} <= names
    positions = [
        m["position"]
        for m in messages
        if m["type"] == "SetPositionMessage" and m["name"] == "/vehicles/alpha"
    ]
    # Only the newest position is replayed, and it is the vehicle's position now.
    assert len(positions) == 1
    np.testing.assert_allclose(positions[0], latest, atol=1e-6)


def test_a_trail_is_redrawn_at_a_bounded_rate_and_catches_up_when_the_vehicle_stops(
    viz: VizServer, scene: FleetScene
) -> None:
    def at(t: float, metres_north: float) -> None:
        lat = HOME[0] + metres_north / 111_200.0
        scene.apply([_summary("alpha", t, lat=lat, lon=HOME[1], alt_msl=500.0)])

    at(0.0, 0.0)
    at(1.0, 2.0)  # the first segment: drawn
    first = np.asarray(_node(viz.viser, "/trails/alpha").points).copy()
    at(1.1, 3.0)  # 0.1 s later: kept, not sent
    np.testing.assert_array_equal(_node(viz.viser, "/trails/alpha").points, first)
    at(1.7, 3.0)  # stopped there: the kept point is drawn once the period has passed
    drawn = _node(viz.viser, "/trails/alpha").points
    assert len(drawn) == 2
    np.testing.assert_allclose(
        drawn[-1][1], _node(viz.viser, "/vehicles/alpha").position, atol=1e-2
    )


def test_reframing_between_two_origins_matches_the_geodesy_round_trip() -> None:
    site = LocalFrame(*HOME)
    other = LocalFrame(47.41, 8.53, 500.0)  # 1.6 km away, 12 m higher
    points = np.random.default_rng(0).uniform(-3000, 3000, (50, 3))
    expected = []
    for east, north, up in points:
        where = site.from_enu(east, north, up)
        expected.append(other.to_enu(where.lat, where.lon, where.alt))
    np.testing.assert_allclose(reframe(points, site, other), expected, atol=1e-6)
