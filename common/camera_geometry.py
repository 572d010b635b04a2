"""The nadir camera's geometry: which point of a flat ground each pixel of a photo sees.

One definition, shared by the simulator (which renders the photo a pose would take) and
the hub (which puts the photo back on the ground from its pose), so that the two are exact
inverses. Plain Python (no numpy): it ships with the agent's leaf packages.

Conventions:
- Image: OpenCV's. Column u grows to the right, row v grows down, and integer coordinates
  are pixel centres, so the principal point of a W x H image is ((W - 1) / 2, (H - 1) / 2).
  Pixels are square with QGroundControl's focal length in pixels,
  f = focal_length_mm * image_width_px / sensor_width_mm.
- Camera frame: x along the image's columns, y along its rows, z out of the lens.
- Mounting: the camera looks straight down the body's z axis with the top of the image
  towards the nose, so camera x = body right, camera y = body backwards, camera z = body down.
- Body attitude: aerospace Z-Y-X (yaw, then pitch, then roll) from north-east-down, yaw
  clockwise from true north, pitch nose-up, roll right-wing-down (``PhotoPose``).
- Ground: a horizontal plane; points on it are (east, north) metres in a local
  east-north-up frame (common.geodesy.LocalFrame), here relative to the camera's nadir.
"""

from __future__ import annotations

import math

from protocol.photos import CameraIntrinsics, PhotoPose

Matrix = tuple[tuple[float, float, float], tuple[float, float, float], tuple[float, float, float]]


def _mul(a: Matrix, b: Matrix) -> Matrix:
    rows = tuple(
        tuple(sum(a[i][k] * b[k][j] for k in range(3)) for j in range(3)) for i in range(3)
    )
    return rows  # type: ignore[return-value]


def focal_px(camera: CameraIntrinsics) -> float:
    """The focal length in pixels (square pixels, from the sensor's width, as QGC does)."""
    return camera.focal_length_mm * camera.image_width_px / camera.sensor_width_mm


def principal_point(camera: CameraIntrinsics) -> tuple[float, float]:
    return (camera.image_width_px - 1) / 2.0, (camera.image_height_px - 1) / 2.0


def gsd_m(camera: CameraIntrinsics, height_m: float) -> float:
    """Metres of ground per pixel straight below a level camera ``height_m`` above it: the
    ground sample distance (QGC's, CameraCalc.cc: height * sensor width / (image width *
    focal length)), the one formula the survey planner, the mosaic and the simulator use."""
    return height_m / focal_px(camera)


def height_for_gsd_m(camera: CameraIntrinsics, gsd: float) -> float:
    """The height above the ground at which a level camera sees ``gsd`` metres per pixel."""
    return gsd * focal_px(camera)


def camera_to_enu(pose: PhotoPose) -> Matrix:
    """The rotation taking a direction in the camera frame to east-north-up."""
    r, p, y = (math.radians(a) for a in (pose.roll, pose.pitch, pose.yaw))
    cr, sr, cp, sp, cy, sy = (
        math.cos(r),
        math.sin(r),
        math.cos(p),
        math.sin(p),
        math.cos(y),
        math.sin(y),
    )
    # Body (forward-right-down) to north-east-down: Rz(yaw) Ry(pitch) Rx(roll).
    body_to_ned: Matrix = (
        (cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr),
        (sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr),
        (-sp, cp * sr, cp * cr),
    )
    ned_to_enu: Matrix = ((0.0, 1.0, 0.0), (1.0, 0.0, 0.0), (0.0, 0.0, -1.0))
    # Camera (x right, y down the image, z out of the lens) in body axes: columns are the
    # camera's axes: x = body y (right), y = -body x (backwards), z = body z (down).
    camera_to_body: Matrix = ((0.0, -1.0, 0.0), (1.0, 0.0, 0.0), (0.0, 0.0, 1.0))
    return _mul(ned_to_enu, _mul(body_to_ned, camera_to_body))


def image_to_ground(pose: PhotoPose, camera: CameraIntrinsics, height_m: float) -> Matrix:
    """The homography taking a pixel (u, v, 1) to the ground point (east, north, 1) it sees,
    in metres from the camera's nadir, for a camera ``height_m`` above the ground plane.

    A pixel's ray is d = R K^-1 (u, v, 1); it meets the plane ``height_m`` below the camera
    at t = height / -d_up, so (east, north) = height * (d_e, d_n) / -d_up: linear in
    (u, v, 1) up to the scale -d_up, a homography. Pixels whose ray points at or above the
    horizon have a third coordinate <= 0 and see no ground.
    """
    f = focal_px(camera)
    cx, cy = principal_point(camera)
    k_inv: Matrix = ((1.0 / f, 0.0, -cx / f), (0.0, 1.0 / f, -cy / f), (0.0, 0.0, 1.0))
    m = _mul(camera_to_enu(pose), k_inv)
    east, north, up = m
    return (
        (height_m * east[0], height_m * east[1], height_m * east[2]),
        (height_m * north[0], height_m * north[1], height_m * north[2]),
        (-up[0], -up[1], -up[2]),
    )
