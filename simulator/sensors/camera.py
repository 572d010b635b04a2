"""The simulated camera's photo: the nadir view of the synthetic ground from a pose.

A pinhole camera looking down the body's z axis, top of the image towards the nose; the
conventions (image, body, attitude, east-north-up) are common/camera_geometry.py's, which
the hub's mosaic uses to put the photo back on the ground. Each pixel's ray meets the ground
plane at the ground's elevation; for a plane that map is a homography, so the ground points
of all pixels come from one 3 x 3 matrix, and the colours from the ground's texture
(vectorised, cv2.remap). Rays at or above the horizon see a plain sky.

The camera's height above the ground is ``pose.alt_msl - ground.elevation_msl``, measured
at the camera's position in the ground's east-north-up frame (the plane is the frame's
tangent plane: over a survey's few hundred metres it leaves the Earth's surface by
millimetres).
"""

from __future__ import annotations

import numpy as np

from common.camera_geometry import gsd_m, image_to_ground
from protocol.photos import CameraIntrinsics, PhotoPose
from simulator.world.ground import Ground, Image

SKY_RGB = (170, 200, 235)


class BelowGround(ValueError):
    """The camera is at or below the ground plane: there is no photo to take."""


def render_nadir(pose: PhotoPose, camera: CameraIntrinsics, ground: Ground) -> Image:
    """The photo (RGB, uint8, image_height_px x image_width_px x 3) the camera takes at
    ``pose`` over ``ground``."""
    east0, north0, up0 = ground.frame.to_enu(pose.lat, pose.lon, pose.alt_msl)
    if up0 <= 0.0:
        raise BelowGround(f"the camera is {up0:.2f} m from the ground plane; it must be above it")
    h = np.array(image_to_ground(pose, camera, up0))
    width, height = camera.image_width_px, camera.image_height_px
    u = np.arange(width, dtype=np.float64)[None, :]
    v = np.arange(height, dtype=np.float64)[:, None]
    w = h[2, 0] * u + h[2, 1] * v + h[2, 2]
    sees_ground = w > 1e-9
    w_safe = np.where(sees_ground, w, 1.0)
    east = (h[0, 0] * u + h[0, 1] * v + h[0, 2]) / w_safe + east0
    north = (h[1, 0] * u + h[1, 1] * v + h[1, 2]) / w_safe + north0
    photo = ground.sample(east, north, gsd_m(camera, up0))
    if not sees_ground.all():
        photo[~sees_ground] = SKY_RGB
    return photo
