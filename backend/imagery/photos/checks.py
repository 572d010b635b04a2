"""What makes the hub refuse a photo, each with a code (counted) and a reason (told).

Pure functions of the photo, its metadata and its survey: the ingest service calls them
as soon as each can be answered (the pose at the first chunk, the image after the last).
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import StrEnum
from pathlib import Path

from PIL import Image, UnidentifiedImageError
from shapely.geometry import Point

from backend.survey.flight.run import SurveyRun, geometry
from backend.survey.planning.camera import preset
from backend.survey.planning.schemas import ManualCamera
from protocol.photos import CameraIntrinsics, PhotoPose


class Refusal(StrEnum):
    NO_POSE = "no_pose"
    BAD_METADATA = "bad_metadata"
    TOO_LARGE = "too_large"
    QUOTA = "quota"
    UPLOADS_IN_PROGRESS = "uploads_in_progress"  # a vehicle's uploads at once
    UNKNOWN_SURVEY = "unknown_survey"
    FAR_FROM_SURVEY = "far_from_survey"
    CORRUPT_IMAGE = "corrupt_image"
    WRONG_IMAGE_SIZE = "wrong_image_size"
    OTHER_VEHICLE = "other_vehicle"


@dataclass(frozen=True)
class Refused(Exception):
    code: Refusal
    reason: str
    status: int = 422

    def __str__(self) -> str:
        return self.reason


def survey_image_size(run: SurveyRun) -> tuple[int, int] | None:
    """The survey camera's image size; None for a manual camera (it has no figures)."""
    camera = run.request.camera
    if isinstance(camera, str):
        model = preset(camera)
        return model.image_width_px, model.image_height_px
    if isinstance(camera, ManualCamera):
        return None
    return camera.image_width_px, camera.image_height_px


def check_against_survey(
    pose: PhotoPose, camera: CameraIntrinsics, run: SurveyRun, margin_m: float
) -> None:
    """The photo belongs to this survey: taken over (or near) its area, by its camera."""
    geo = geometry(run)
    x, y = geo.frame.to_local(pose.lat, pose.lon)
    outside_m = float(geo.area.distance(Point(x, y)))
    if outside_m > margin_m:
        raise Refused(
            Refusal.FAR_FROM_SURVEY,
            f"the photo's position ({pose.lat:.6f}, {pose.lon:.6f}) is {outside_m:.0f} m "
            f"outside survey {run.id}'s area (at most {margin_m:.0f} m is taken)",
        )
    size = (camera.image_width_px, camera.image_height_px)
    expected = survey_image_size(run)
    if expected is not None and size != expected:
        width, height = expected
        raise Refused(
            Refusal.WRONG_IMAGE_SIZE,
            f"the photo's camera is {size[0]}x{size[1]} px; survey {run.id}'s camera "
            f"model is {width}x{height} px",
        )


def check_image(path: Path, camera: CameraIntrinsics) -> None:
    """A whole JPEG of the camera model's size. Decoded at an eighth of its size (the
    JPEG decoder's own scaling), which still reads every byte of the compressed data, so a
    truncated or corrupt file is found at a fraction of a full decode's cost."""
    try:
        with Image.open(path) as image:
            if image.format != "JPEG":
                raise Refused(Refusal.CORRUPT_IMAGE, f"the photo is {image.format}, not a JPEG")
            size = image.size
            expected = (camera.image_width_px, camera.image_height_px)
            if size != expected:
                raise Refused(
                    Refusal.WRONG_IMAGE_SIZE,
                    f"the image is {size[0]}x{size[1]} px; its camera model says "
                    f"{expected[0]}x{expected[1]} px",
                )
            image.draft("RGB", (max(1, size[0] // 8), max(1, size[1] // 8)))
            image.load()
    except Refused:
        raise
    except Image.DecompressionBombError as error:
        # A header claiming more pixels than any camera has: refused from the header,
        # never decoded (a few KB could otherwise ask for gigabytes).
        raise Refused(Refusal.CORRUPT_IMAGE, f"the photo is not a real image: {error}") from None
    except (UnidentifiedImageError, OSError, SyntaxError, ValueError) as error:
        raise Refused(Refusal.CORRUPT_IMAGE, f"the photo is not a whole JPEG: {error}") from None
