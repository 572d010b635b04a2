"""The camera: photos on request and by distance travelled (AP_Camera)."""

from __future__ import annotations

import math

from simulator.vehicle.events import PhotoTaken
from simulator.vehicle.state import VehicleState


class Camera(VehicleState):
    def take_photo(self) -> None:
        """AP_Camera::take_picture: the shutter fires; CAMERA_FEEDBACK follows."""
        self.photos += 1
        point = self.position()
        body = self.body
        self._cam_last_ne = (body.north, body.east)
        self._events.append(
            PhotoTaken(
                self.photos,
                self.time_s,
                point.lat,
                point.lon,
                point.alt,
                self.relative_alt,
                body.roll,
                body.pitch,
                body.yaw,
            )
        )

    @property
    def _camera_moving(self) -> bool:
        return self.armed

    def _check_camera_distance(self) -> None:
        """AP_Camera: with a trigger distance set, a photo every that many metres moved."""
        if self._cam_trigg_dist <= 0.0 or not self._camera_moving:
            return
        here = (self.body.north, self.body.east)
        if math.dist(here, self._cam_last_ne) >= self._cam_trigg_dist:
            self.take_photo()
