"""A photo the hub has stored, and where it goes next (the live mosaic)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Protocol

from protocol.photos import CameraIntrinsics, PhotoPose


@dataclass(frozen=True)
class StoredPhoto:
    photo_id: str
    vehicle_id: str
    survey_id: str | None
    path: Path  # the geotagged JPEG on the hub's disk
    pose: PhotoPose
    camera: CameraIntrinsics


class PhotoSink(Protocol):
    """Takes each photo once it is stored and checked: the mosaic engine
    (backend/mosaic's MosaicService) is wired here by the hub."""

    async def add_photo(self, photo: StoredPhoto) -> None: ...
