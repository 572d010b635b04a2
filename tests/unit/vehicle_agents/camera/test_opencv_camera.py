"""The OpenCV camera source, on a video file OpenCV opens as it opens a camera."""

from __future__ import annotations

import asyncio
import io
from pathlib import Path

import cv2
import numpy as np
import pytest
from PIL import Image

from protocol.photos import CameraIntrinsics
from vehicle_agents.camera.sources import CaptureError, OpenCvCamera, Shot, open_source

CAMERA = CameraIntrinsics(
    sensor_width_mm=4.8,
    sensor_height_mm=3.6,
    image_width_px=160,
    image_height_px=120,
    focal_length_mm=5.4,
)


def video(path: Path, size: tuple[int, int], frames: int = 5) -> str:
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"MJPG"), 10.0, size)
    for index in range(frames):
        frame = np.full((size[1], size[0], 3), 40 * index, np.uint8)
        writer.write(frame)
    writer.release()
    return f"opencv:{path}"


def test_a_grabbed_frame_is_a_jpeg_of_the_models_size_exposed_at_the_grab(tmp_path: Path) -> None:
    clock = iter([12.5])
    source = OpenCvCamera(video(tmp_path / "cam.avi", (160, 120)), CAMERA, lambda: next(clock))
    try:
        capture = asyncio.run(source.capture(Shot(1, 10.0, 1.7e9)))
    finally:
        source.close()
    assert capture.exposed_at == 12.5  # the grab's instant, for the pose's interpolation
    assert capture.jpeg.startswith(b"\xff\xd8")
    with Image.open(io.BytesIO(capture.jpeg)) as image:
        assert image.size == (160, 120)


def test_a_camera_of_another_size_or_none_at_all_is_a_clear_error(tmp_path: Path) -> None:
    source = open_source(video(tmp_path / "big.avi", (320, 240)), CAMERA, print)
    with pytest.raises(CaptureError, match="delivers 320x240 px, the camera model says 160x120"):
        asyncio.run(source.capture(Shot(1, 0.0, 1.7e9)))
    source.close()
    missing = open_source(f"opencv:{tmp_path / 'none.avi'}", CAMERA, print)
    with pytest.raises(CaptureError, match="could not open"):
        asyncio.run(missing.capture(Shot(1, 0.0, 1.7e9)))
