"""A camera whose files land in a folder: each new whole JPEG paired with the next
trigger by order and time, the card's older files left alone, and every file or trigger
that cannot be paired said, never dropped silently. Real files in a real folder; the
clock is the test's."""

from __future__ import annotations

import asyncio
from pathlib import Path

import pytest

from protocol.photos import PhotoPose
from tests.support.cameras import CAMERA, Clock, feedback, queued, render
from vehicle_agents.camera.folder import EARLY_S, PAIR_WINDOW_S, FolderCamera
from vehicle_agents.camera.queue import PhotoQueue
from vehicle_agents.camera.sources import CaptureError, Shot
from vehicle_agents.camera.trigger import CameraTrigger
from vehicle_agents.sensors.fcu_time import FcuClock, PoseHistory

POSE = PhotoPose(lat=1.0, lon=2.0, alt_msl=3.0, alt_rel=4.0, roll=0.0, pitch=0.0, yaw=0.0, time=0)


class Folder:
    def __init__(self, path: Path, *, mounted: bool = True) -> None:
        self.path = path
        if mounted:
            path.mkdir(parents=True, exist_ok=True)
        self.clock = Clock()
        self.said: list[str] = []
        self.camera = FolderCamera(
            f"folder:{path}",
            CAMERA,
            lambda text, _severity: self.said.append(text),
            monotonic=self.clock,
        )

    def write(self, name: str, data: bytes | None = None) -> Path:
        file = self.path / name
        file.parent.mkdir(parents=True, exist_ok=True)
        file.write_bytes(data if data is not None else render(POSE, CAMERA))
        return file

    def polls(self, count: int = 2, step: float = 0.5) -> None:
        """``count`` polls ``step`` seconds apart: a file unchanged over two is whole."""
        for _ in range(count):
            self.camera.poll()
            self.clock.now += step

    def shot(self, index: int, arrived: float | None = None) -> Shot:
        return Shot(index, self.clock.now if arrived is None else arrived, 0.0, POSE)

    def capture(self, shot: Shot) -> bytes:
        return asyncio.run(self.camera.capture(shot)).jpeg


@pytest.fixture
def folder(tmp_path: Path) -> Folder:
    return Folder(tmp_path / "DCIM")


def test_new_files_go_to_the_triggers_in_order_and_the_cards_old_files_to_none(
    folder: Folder,
) -> None:
    folder.write("100MSDCF/DSC00001.JPG", b"an earlier flight's")
    folder.polls(1)  # the baseline: what is on the card when the agent starts
    first = folder.shot(1)
    second = folder.shot(2)
    folder.write("100MSDCF/DSC00002.JPG", b"\xff\xd8 first")
    folder.write("100MSDCF/DSC00003.jpeg", b"\xff\xd8 second")
    folder.write("100MSDCF/DSC00003.ARW", b"raw beside it: not a JPEG")
    folder.polls()
    assert folder.capture(first) == b"\xff\xd8 first"
    assert folder.capture(second) == b"\xff\xd8 second"
    assert folder.said == []


def test_a_card_mounted_later_brings_no_old_files(tmp_path: Path) -> None:
    folder = Folder(tmp_path / "not-mounted-yet", mounted=False)
    folder.polls(1)
    folder.write("DSC00001.JPG", b"an earlier flight's")  # the card appears, with its files
    folder.polls(3)
    assert not folder.camera._ready
    assert folder.said == []


def test_a_file_still_being_written_waits_until_its_size_holds(folder: Folder) -> None:
    folder.polls(1)
    shot = folder.shot(1)
    file = folder.write("DSC00001.JPG", b"\xff\xd8 half")
    folder.polls(1)
    file.write_bytes(b"\xff\xd8 half and the rest")
    folder.polls(1)  # grown since the last poll: not whole yet
    assert not folder.camera._ready
    folder.polls(1)
    assert folder.capture(shot) == b"\xff\xd8 half and the rest"


def test_a_trigger_with_no_file_in_its_window_takes_no_photo_and_says_so(folder: Folder) -> None:
    folder.polls(1)
    shot = folder.shot(7, arrived=folder.clock.now - PAIR_WINDOW_S - 0.1)
    with pytest.raises(CaptureError, match=r"no new file in .*DCIM within 10 s of the trigger"):
        folder.capture(shot)


def test_a_file_no_trigger_came_for_is_said_and_left_in_the_folder(folder: Folder) -> None:
    folder.polls(1)
    stray = folder.write("DSC00009.JPG")
    folder.polls()
    assert folder.said == []  # a trigger may yet come for it
    folder.clock.now += PAIR_WINDOW_S + EARLY_S
    folder.polls(1)
    assert folder.said == [
        f"camera file {stray} not uploaded: no camera trigger came for it; it stays in the "
        "folder (1 unpaired so far)"
    ]
    assert stray.exists()
    assert folder.camera.unpaired == 1


def test_a_file_from_before_a_trigger_is_not_its_photo(folder: Folder) -> None:
    """The file appeared well before the trigger's message: it is some other shutter's
    (the camera's own button, a trigger the link lost), told as unpaired; the next file
    is the trigger's."""
    folder.polls(1)
    early = folder.write("DSC00010.JPG", b"\xff\xd8 early")
    folder.polls()
    folder.clock.now += EARLY_S + 1.0
    shot = folder.shot(3)
    folder.write("DSC00011.JPG", b"\xff\xd8 its own")
    folder.polls()
    assert folder.capture(shot) == b"\xff\xd8 its own"
    assert folder.said == [
        f"camera file {early} not uploaded: it appeared 4.0 s before the next camera "
        "trigger (photo 3); it stays in the folder (1 unpaired so far)"
    ]


def test_a_file_larger_than_a_photo_may_be_is_refused(tmp_path: Path) -> None:
    folder = Folder(tmp_path)
    folder.camera.max_bytes = 100
    folder.polls(1)
    shot = folder.shot(1)
    big = folder.write("DSC00001.JPG", b"\xff" * 101)
    folder.polls()
    with pytest.raises(CaptureError, match=f"{big} is larger than the 100 bytes"):
        folder.capture(shot)


def test_no_folder_is_refused() -> None:
    with pytest.raises(ValueError, match="folder:/PATH"):
        FolderCamera("folder:", CAMERA, lambda text, severity: None)


def test_the_autopilots_feedback_poses_the_folders_file(tmp_path: Path) -> None:
    """Through the trigger: ArduPilot's CAMERA_FEEDBACK is the shutter, the folder's
    new file its photo, posed and geotagged with the feedback's pose."""
    folder = Folder(tmp_path / "card")
    folder.polls(1)

    async def take() -> CameraTrigger:
        poses = PoseHistory(FcuClock(), monotonic=folder.clock)
        queue = PhotoQueue(tmp_path / "queue", budget_bytes=10_000_000)
        trigger = CameraTrigger(
            "cam_1", folder.camera, poses, queue, lambda t, s: None, monotonic=folder.clock
        )
        trigger.on_message(feedback(5, -35.3632621, 149.1652374))
        folder.write("DSC00001.JPG")
        folder.polls()
        await queued(trigger)
        return trigger

    trigger = asyncio.run(take())
    photo = trigger.queue.oldest()
    assert photo is not None
    assert photo.meta.index == 5
    assert (photo.meta.pose.lat, photo.meta.pose.lon) == (-35.3632621, 149.1652374)
    assert folder.said == []
