"""A photo the hub has stored and hands to the mosaic: where it is on disk and how it was
taken (the pose and camera the agent's upload declared, protocol/photos.py)."""

from __future__ import annotations

import pathlib
from dataclasses import dataclass

from protocol.photos import CameraIntrinsics, PhotoPose


@dataclass(frozen=True, slots=True)
class StoredPhoto:
    photo_id: str
    vehicle_id: str
    survey_id: str
    path: pathlib.Path  # the JPEG on disk
    pose: PhotoPose
    camera: CameraIntrinsics
