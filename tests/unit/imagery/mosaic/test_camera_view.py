"""The simulated camera's nadir view (simulator/sensors/camera.py) over the synthetic ground:
targets appear where the pinhole geometry puts them, for a level camera, a rolled one and
a turned one."""

from __future__ import annotations

import math

import cv2
import numpy as np
import pytest

from common.camera_geometry import focal_px
from protocol.photos import CameraIntrinsics, PhotoPose
from simulator.sensors.camera import BelowGround, render_nadir
from simulator.world.ground import ARUCO_DICTIONARY, Ground, GroundTarget

HOME = (-35.363261, 149.165230, 584.0)
CAMERA = CameraIntrinsics(
    sensor_width_mm=13.2,
    sensor_height_mm=8.8,
    image_width_px=640,
    image_height_px=480,
    focal_length_mm=8.8,
)


@pytest.fixture(scope="module")
def ground() -> Ground:
    lat, lon, alt = HOME
    return Ground(lat, lon, alt, seed=7, targets=(GroundTarget(7, lat, lon, 1.5),))


def pose(**change: float) -> PhotoPose:
    lat, lon, alt = HOME
    values = {"lat": lat, "lon": lon, "alt_msl": alt + 30.0, "alt_rel": 30.0}
    values |= {"roll": 0.0, "pitch": 0.0, "yaw": 0.0, "time": 1.0} | change
    return PhotoPose(**values)


def detect(photo: np.ndarray) -> dict[int, np.ndarray]:
    detector = cv2.aruco.ArucoDetector(
        cv2.aruco.getPredefinedDictionary(ARUCO_DICTIONARY), cv2.aruco.DetectorParameters()
    )
    corners, ids, _ = detector.detectMarkers(photo)
    return (
        {}
        if ids is None
        else {int(i): c.reshape(4, 2) for i, c in zip(ids.ravel(), corners, strict=True)}
    )


def test_a_level_camera_sees_the_target_below_it_at_the_image_centre(ground: Ground) -> None:
    photo = render_nadir(pose(), CAMERA, ground)
    assert photo.shape == (480, 640, 3)
    assert photo.dtype == np.uint8
    corners = detect(photo)[7]
    centre = corners.mean(axis=0)
    assert np.allclose(centre, (319.5, 239.5), atol=1.0)
    # 1.5 m at 30 m high with f = 426.7 px is 21.3 px a side.
    side = np.linalg.norm(corners[1] - corners[0])
    assert side == pytest.approx(1.5 * focal_px(CAMERA) / 30.0, abs=1.5)


def test_rolling_right_wing_down_moves_the_target_right_by_f_tan_roll(ground: Ground) -> None:
    photo = render_nadir(pose(roll=8.0), CAMERA, ground)
    centre = detect(photo)[7].mean(axis=0)
    assert centre[0] - 319.5 == pytest.approx(focal_px(CAMERA) * math.tan(math.radians(8)), abs=1.5)
    assert centre[1] == pytest.approx(239.5, abs=1.0)


def test_pitching_nose_up_moves_the_target_towards_the_bottom(ground: Ground) -> None:
    centre = detect(render_nadir(pose(pitch=8.0), CAMERA, ground))[7].mean(axis=0)
    # Nose up, the belly and the lens turn forward: what is below appears behind, lower down.
    assert centre[1] - 239.5 == pytest.approx(focal_px(CAMERA) * math.tan(math.radians(8)), abs=1.5)


def test_yaw_turns_the_ground_the_other_way_in_the_image(ground: Ground) -> None:
    level = detect(render_nadir(pose(), CAMERA, ground))[7]
    turned = detect(render_nadir(pose(yaw=90.0), CAMERA, ground))[7]
    # Facing east, north (the marker's top edge) is on the image's left.
    top_edge = level[1] - level[0]
    turned_edge = turned[1] - turned[0]
    assert top_edge[0] > 0
    assert abs(top_edge[1]) < 1.0
    assert turned_edge[1] < 0
    assert abs(turned_edge[0]) < 1.0


def test_the_ground_is_the_same_from_the_same_seed_and_differs_elsewhere(ground: Ground) -> None:
    lat, lon, alt = HOME
    again = Ground(lat, lon, alt, seed=7, targets=ground.targets)
    assert np.array_equal(render_nadir(pose(), CAMERA, ground), render_nadir(pose(), CAMERA, again))
    moved = render_nadir(pose(lat=lat + 0.001), CAMERA, ground)
    assert np.abs(moved.astype(int) - render_nadir(pose(), CAMERA, ground)).mean() > 10


def test_a_camera_below_the_ground_is_refused(ground: Ground) -> None:
    with pytest.raises(BelowGround, match="above it"):
        render_nadir(pose(alt_msl=HOME[2] - 1.0), CAMERA, ground)
