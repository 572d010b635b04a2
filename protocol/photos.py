"""Photos on the wire: what an agent's upload says about each photo, besides its bytes.

The photo itself travels over HTTP (``PUT /api/v1/vehicles/{vehicle_id}/photos/{photo_id}``,
resumable in chunks), never on the telemetry socket, so that a burst of 12 MP images
cannot starve telemetry. Its pose and camera also ride inside the JPEG as EXIF/XMP for
the offline photogrammetry tools; this record is what the hub trusts and validates.
"""

from __future__ import annotations

from typing import Annotated

from pydantic import BaseModel, ConfigDict, Field

PhotoId = Annotated[str, Field(pattern=r"^[A-Za-z0-9_.-]{1,80}$")]
MAX_PHOTO_BYTES = 40 * 1024 * 1024  # a 12 MP JPEG at high quality is 5-10 MB


class PhotoPose(BaseModel):
    """Where the camera was at the exposure instant (interpolated to it): WGS84 position,
    altitudes in metres (above mean sea level and above home), attitude in degrees of the
    vehicle body (roll right-wing-down, pitch nose-up, yaw clockwise from true north), and
    the time in Unix seconds. The camera looks straight down the body's z axis (nadir)."""

    model_config = ConfigDict(extra="forbid", frozen=True)

    lat: float = Field(ge=-90, le=90)
    lon: float = Field(ge=-180, le=180)
    alt_msl: float = Field(ge=-500, le=10_000)
    alt_rel: float = Field(ge=-500, le=10_000)
    roll: float = Field(ge=-180, le=180)
    pitch: float = Field(ge=-90, le=90)
    yaw: float = Field(ge=-360, le=360)
    time: float = Field(ge=0)


class CameraIntrinsics(BaseModel):
    """The pinhole camera that took the photo (the survey's camera model)."""

    model_config = ConfigDict(extra="forbid", frozen=True)

    sensor_width_mm: float = Field(gt=0, le=100)
    sensor_height_mm: float = Field(gt=0, le=100)
    image_width_px: int = Field(gt=0, le=20_000)
    image_height_px: int = Field(gt=0, le=20_000)
    focal_length_mm: float = Field(gt=0, le=1_000)


class PhotoMeta(BaseModel):
    """Sent with a photo's first chunk: which survey, which shot, its pose and camera."""

    model_config = ConfigDict(extra="forbid", frozen=True)

    photo_id: PhotoId
    survey_id: str | None = Field(default=None, max_length=80)
    index: int = Field(ge=0)  # the camera's shot counter (CAMERA_FEEDBACK img_idx)
    size_bytes: int = Field(gt=0, le=MAX_PHOTO_BYTES)
    pose: PhotoPose
    camera: CameraIntrinsics


def parse_camera_model(text: str) -> CameraIntrinsics:
    """``sensor_w,sensor_h,width_px,height_px,focal``: millimetres and pixels."""
    parts = text.split(",")
    try:
        if len(parts) != 5:
            raise ValueError
        return CameraIntrinsics(
            sensor_width_mm=float(parts[0]),
            sensor_height_mm=float(parts[1]),
            image_width_px=int(parts[2]),
            image_height_px=int(parts[3]),
            focal_length_mm=float(parts[4]),
        )
    except ValueError:
        raise ValueError(
            "expected sensor width,height (mm),image width,height (px),focal length (mm), "
            f"e.g. 13.2,8.8,5472,3648,8.8; got {text!r}"
        ) from None


def format_camera_model(camera: CameraIntrinsics) -> str:
    """The camera in the form `parse_camera_model` reads (an agent's --camera-model)."""
    return ",".join(
        f"{value:g}"
        for value in (
            camera.sensor_width_mm,
            camera.sensor_height_mm,
            camera.image_width_px,
            camera.image_height_px,
            camera.focal_length_mm,
        )
    )


def describe_camera(camera: CameraIntrinsics) -> str:
    """The camera's figures for a person: "6.3x4.7 mm, 1600x1200 px, 4.5 mm"."""
    return (
        f"{camera.sensor_width_mm:g}x{camera.sensor_height_mm:g} mm, "
        f"{camera.image_width_px}x{camera.image_height_px} px, {camera.focal_length_mm:g} mm"
    )
