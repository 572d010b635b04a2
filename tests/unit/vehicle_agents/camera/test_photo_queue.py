"""The onboard photo queue: on disk, oldest first, within its budget, across restarts."""

from __future__ import annotations

import os
from pathlib import Path

from protocol.photos import CameraIntrinsics, PhotoMeta, PhotoPose
from vehicle_agents.camera.queue import PhotoQueue

CAMERA = CameraIntrinsics(
    sensor_width_mm=13.2,
    sensor_height_mm=8.8,
    image_width_px=96,
    image_height_px=64,
    focal_length_mm=8.8,
)


def meta(index: int, size: int) -> PhotoMeta:
    pose = PhotoPose(lat=1, lon=2, alt_msl=3, alt_rel=4, roll=0, pitch=0, yaw=0, time=1e9 + index)
    return PhotoMeta(photo_id=f"v-{index}", index=index, size_bytes=size, pose=pose, camera=CAMERA)


def put(queue: PhotoQueue, index: int, size: int = 1000) -> None:
    queue.put(meta(index, size), b"\xff\xd8" + bytes(size - 2))


def test_over_budget_the_oldest_photos_are_deleted_counted_and_told(tmp_path: Path) -> None:
    told: list[str] = []
    queue = PhotoQueue(tmp_path, budget_bytes=3500, notify=lambda text, severity: told.append(text))
    for index in range(5):
        put(queue, index)
    oldest = queue.oldest()
    assert oldest is not None
    assert oldest.photo_id == "v-2"
    assert len(queue) == 3
    assert queue.size_bytes == 3000
    assert queue.dropped == 2
    assert len(told) == 2
    assert "v-0" in told[0]
    assert "budget" in told[0]
    assert sorted(p.name for p in tmp_path.iterdir()) == [
        f"v-{i}.{ext}" for i in (2, 3, 4) for ext in ("jpg", "json")
    ]


def test_a_restarted_agent_finds_its_queue_in_order_and_clears_half_writes(tmp_path: Path) -> None:
    queue = PhotoQueue(tmp_path, budget_bytes=10_000)
    for index in (7, 3, 5):  # queued in this order; ids do not sort that way
        put(queue, index)
        # distinct modification times, however coarse the file system's clock
        os.utime(tmp_path / f"v-{index}.json", ns=(index, 10**9 * (10 + len(queue))))
    (tmp_path / "v-9.jpg").write_bytes(b"half")  # its JSON was never written
    (tmp_path / "v-8.jpg.tmp").write_bytes(b"cut")
    again = PhotoQueue(tmp_path, budget_bytes=10_000)
    order = []
    while (photo := again.oldest()) is not None:
        order.append(photo.photo_id)
        again.remove(photo.photo_id, uploaded=True)
    assert order == ["v-7", "v-3", "v-5"]
    assert again.uploaded == 3
    assert list(tmp_path.iterdir()) == []


def test_photos_being_uploaded_are_skipped(tmp_path: Path) -> None:
    queue = PhotoQueue(tmp_path, budget_bytes=10_000)
    put(queue, 1)
    put(queue, 2)
    photo = queue.oldest(skip={"v-1"})
    assert photo is not None
    assert photo.photo_id == "v-2"
    assert photo.path.read_bytes().startswith(b"\xff\xd8")
