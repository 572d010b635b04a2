"""From the autopilot's camera trigger to a posed, geotagged photo in the onboard queue.

The mission's camera commands (DO_SET_CAM_TRIGG_DIST, DO_DIGICAM_CONTROL) make the
autopilot fire the camera, and it says so at the shutter, in its own way:

- ArduPilot's AP_Camera sends CAMERA_FEEDBACK, with its shot counter (``img_idx``, from 1)
  and the vehicle's position and attitude at that instant;
- PX4's camera_trigger module sends CAMERA_TRIGGER, with its sequence number (``seq``,
  from 0) but no pose (the agent asks for it: PX4 streams it to a GCS link only on
  request), and its camera_feedback module CAMERA_IMAGE_CAPTURED, with the same number
  (``image_index``), the position and the attitude (a quaternion) at the shutter.

With a MAVLink camera as the source (``--camera mavlink``) the camera itself tells of
each photo, with CAMERA_IMAGE_CAPTURED from its own component and the file's address:
that message is the shutter, and the autopilot's make no photo.

Each shutter is one photo, whichever of its messages comes first (`ShutterMatcher`
matches PX4's two by their index): the source takes (or fetches) it, the pose at its
exposure is found, and the JPEG is geotagged and queued for upload. A trigger that makes
no photo says why, in an event and the log, and is counted in `CameraStats`.
"""

from __future__ import annotations

import asyncio
import logging
import math
import time
from collections import OrderedDict
from collections.abc import Callable
from dataclasses import dataclass, replace
from typing import Any

from protocol.photos import PhotoMeta, PhotoPose
from vehicle_agents.camera.geotag import NotAJpeg, geotag
from vehicle_agents.camera.queue import PhotoQueue
from vehicle_agents.camera.sources import CameraSource, Capture, CaptureError, Shot
from vehicle_agents.sensors.fcu_time import PoseHistory
from vehicle_agents.telemetry.shutters import (
    MATCH_WINDOW_S,
    ShutterMatcher,
    captured_alt_rel,
    from_autopilot,
)

log = logging.getLogger(__name__)

CAMERA_FEEDBACK_PHOTO = 0  # CAMERA_FEEDBACK_FLAGS: a photo (not video, not a bad capture)
CAPTURE_FAILED = 0  # CAMERA_IMAGE_CAPTURED.capture_result: 1 success, 0 failure
KEPT_PHOTOS = 256  # a MAVLink camera's newest photos remembered, against resends
SHOT_QUEUE = 64  # triggers waiting for their photo; more are dropped and counted
POSE_WAIT_S = 0.5  # how long a photo waits for the flight controller's pose to cover it
POSE_POLL_S = 0.02
PLAUSIBLE_EPOCH_S = 1e9  # a time_usec below this (2001) is not a Unix time

Notify = Callable[[str, int], None]
SEVERITY_WARNING = 4


@dataclass
class CameraStats:
    triggers: int = 0
    queued: int = 0
    capture_failed: int = 0
    no_pose: int = 0
    dropped_triggers: int = 0
    failed_on_board: int = 0  # the camera said the capture failed (CAMERA_IMAGE_CAPTURED)
    repeats: int = 0  # a second message of a shutter already counted (PX4 sends two)


class CameraTrigger:
    """An FcuLink listener (`on_message`) and the task (`run`) that turns each of the
    autopilot's camera triggers into a queued photo."""

    def __init__(
        self,
        vehicle_id: str,
        source: CameraSource,
        poses: PoseHistory,
        queue: PhotoQueue,
        notify: Notify,
        *,
        monotonic: Callable[[], float] = time.monotonic,
        wall: Callable[[], float] = time.time,
    ) -> None:
        self.vehicle_id = vehicle_id
        self.source = source
        self.poses = poses
        self.queue = queue
        self._notify = notify
        self._monotonic = monotonic
        self._wall = wall
        self._shots: asyncio.Queue[Shot] = asyncio.Queue(maxsize=SHOT_QUEUE)
        self._home_msl: float | None = None  # for the height above home of interpolated poses
        self._shutters = ShutterMatcher()
        # A MAVLink camera's photos already taken, by (image_index, time_utc): a message
        # it sends again (another GCS asks for a missing one by its index) is the same
        # photo, while a restarted camera's index 0 comes with another time.
        self._camera_photos: OrderedDict[tuple[int, int], None] = OrderedDict()
        # CAMERA_IMAGE_CAPTURED's poses (and arrivals) for shots whose CAMERA_TRIGGER
        # came first, the newest SHOT_QUEUE of them
        self._late_poses: dict[int, tuple[float, PhotoPose]] = {}
        self._photo_ids: set[str] = set()  # taken in this run: no photo overwrites another
        self.stats = CameraStats()

    def on_message(self, message: Any) -> None:
        kind = message.get_type()
        if kind == "GLOBAL_POSITION_INT" and (message.lat or message.lon):
            self._home_msl = message.alt / 1000.0 - message.relative_alt / 1000.0
        elif self.source.announces_shots:
            # A MAVLink camera's own CAMERA_IMAGE_CAPTURED is the photo; the autopilot's
            # trigger messages (which may well fire that camera) make none of their own.
            if kind == "CAMERA_IMAGE_CAPTURED" and not from_autopilot(message):
                self._camera_captured(message)
        elif kind == "CAMERA_FEEDBACK" and int(message.flags) == CAMERA_FEEDBACK_PHOTO:
            self._triggered(kind, self.shot_of(message))
        elif kind == "CAMERA_TRIGGER":
            self._triggered(kind, self.shot_of_trigger(message))
        elif kind == "CAMERA_IMAGE_CAPTURED" and from_autopilot(message):
            self._captured(message)

    def _captured(self, message: Any) -> None:
        shot = self.shot_of_captured(message)
        if int(message.capture_result) != CAPTURE_FAILED:
            self._triggered("CAMERA_IMAGE_CAPTURED", shot)
        elif self._shutters.is_new("CAMERA_IMAGE_CAPTURED", shot.index, shot.arrived):
            self._failed_on_board(shot)

    def _camera_captured(self, message: Any) -> None:
        key = (int(message.image_index), int(message.time_utc))
        if key in self._camera_photos:
            self.stats.repeats += 1
            return
        self._camera_photos[key] = None
        while len(self._camera_photos) > KEPT_PHOTOS:
            self._camera_photos.popitem(last=False)
        shot = self.shot_of_captured(message)
        if int(message.capture_result) == CAPTURE_FAILED:
            self._failed_on_board(shot)
        else:
            self.stats.triggers += 1
            self._enqueue(shot)

    def _failed_on_board(self, shot: Shot) -> None:
        self.stats.triggers += 1
        self.stats.failed_on_board += 1
        self._notify(f"photo {shot.index} not taken: the camera failed", SEVERITY_WARNING)

    def _triggered(self, kind: str, shot: Shot) -> None:
        if not self._shutters.is_new(kind, shot.index, shot.arrived):
            self.stats.repeats += 1
            if shot.feedback_pose is not None:  # the better pose, for the shot still waiting
                self._late_poses[shot.index] = (shot.arrived, shot.feedback_pose)
                while len(self._late_poses) > SHOT_QUEUE:
                    del self._late_poses[next(iter(self._late_poses))]
            return
        self.stats.triggers += 1
        self._enqueue(shot)

    def _enqueue(self, shot: Shot) -> None:
        try:
            self._shots.put_nowait(shot)
        except asyncio.QueueFull:
            self.stats.dropped_triggers += 1
            self._notify(
                f"photo {shot.index} not taken: {SHOT_QUEUE} triggers already wait for the "
                f"camera ({self.stats.dropped_triggers} dropped so far)",
                SEVERITY_WARNING,
            )

    def shot_of_captured(self, message: Any) -> Shot:
        """PX4's CAMERA_IMAGE_CAPTURED: the camera_feedback module's record of the shutter,
        with the vehicle's position and attitude (camera_feedback copies them from the
        estimator at the trigger)."""
        time_utc = int(message.time_utc)
        utc = time_utc / 1e6 if time_utc / 1e6 > PLAUSIBLE_EPOCH_S else self._wall()
        pose = None
        if message.lat or message.lon:  # 0, 0: no position to give
            roll, pitch, yaw = _euler(message.q)
            pose = PhotoPose(
                lat=message.lat / 1e7,
                lon=message.lon / 1e7,
                alt_msl=message.alt / 1000.0,
                alt_rel=captured_alt_rel(message, self._home_msl),
                roll=_degrees(math.degrees(roll), 180.0),
                pitch=max(-90.0, min(90.0, math.degrees(pitch))),
                yaw=math.degrees(yaw) % 360.0,
                time=utc,
            )
        file_url = str(message.file_url).split("\0", 1)[0].strip()  # NUL-padded char[205]
        return Shot(int(message.image_index), self._monotonic(), utc, pose, file_url or None)

    def shot_of_trigger(self, message: Any) -> Shot:
        """PX4's CAMERA_TRIGGER: no pose in it, so the photo is posed from the streams at
        the trigger's arrival (a serial link brings it within milliseconds of the shutter,
        and the streams' own latency is the same, so the two line up on the flight
        controller's clock)."""
        time_usec = int(message.time_usec)
        utc = time_usec / 1e6 if time_usec / 1e6 > PLAUSIBLE_EPOCH_S else self._wall()
        return Shot(int(message.seq), self._monotonic(), utc, None)

    def shot_of(self, message: Any) -> Shot:
        arrived = self._monotonic()
        time_usec = int(message.time_usec)
        # ArduPilot stamps it with the GPS's Unix time; 0 (or time since boot) without one.
        utc = time_usec / 1e6 if time_usec / 1e6 > PLAUSIBLE_EPOCH_S else self._wall()
        pose = None
        if message.lat or message.lng:  # 0, 0: the autopilot had no position to give
            pose = PhotoPose(
                lat=message.lat / 1e7,
                lon=message.lng / 1e7,
                alt_msl=float(message.alt_msl),
                alt_rel=float(message.alt_rel),
                roll=_degrees(float(message.roll), 180.0),
                pitch=max(-90.0, min(90.0, float(message.pitch))),
                yaw=float(message.yaw) % 360.0,
                time=utc,
            )
        return Shot(int(message.img_idx), arrived, utc, pose)

    async def run(self) -> None:
        while True:
            shot = await self._shots.get()
            late = self._late_poses.pop(shot.index, None)
            if (
                late is not None
                and shot.feedback_pose is None
                and abs(late[0] - shot.arrived) <= MATCH_WINDOW_S  # not a rebooted counter's
            ):
                shot = replace(shot, feedback_pose=late[1])
            try:
                await self.take(shot)
            except CaptureError as error:
                self.stats.capture_failed += 1
                self._notify(f"photo {shot.index} not taken: {error}", SEVERITY_WARNING)
            except (NotAJpeg, OSError) as error:
                self.stats.capture_failed += 1
                self._notify(f"photo {shot.index} not stored: {error}", SEVERITY_WARNING)

    async def take(self, shot: Shot) -> str | None:
        """Capture, pose, geotag and queue one shot; its photo id, or None without a pose."""
        capture = await self.source.capture(shot)
        pose = await self.pose_of(shot, capture)
        if pose is None:
            self.stats.no_pose += 1
            self._notify(
                f"photo {shot.index} not kept: the flight controller's pose does not cover "
                "its exposure",
                SEVERITY_WARNING,
            )
            return None
        camera = self.source.camera
        tagged = await asyncio.to_thread(
            geotag, capture.jpeg, pose, camera, model=type(self.source).__name__
        )
        photo_id = self._photo_id(pose.time, shot.index)
        meta = PhotoMeta(
            photo_id=photo_id, index=shot.index, size_bytes=len(tagged), pose=pose, camera=camera
        )
        await asyncio.to_thread(self.queue.put, meta, tagged)
        self.stats.queued += 1
        return photo_id

    def _photo_id(self, utc: float, index: int) -> str:
        """The photo's id: the vehicle, the exposure's millisecond and the shot counter,
        told apart from any earlier photo of this run with the same (two shutters in one
        millisecond with one number), which the queue would otherwise overwrite."""
        base = f"{self.vehicle_id}-{round(utc * 1000)}-{index:05d}"
        photo_id, n = base, 1
        while photo_id in self._photo_ids:
            n += 1
            photo_id = f"{base}-{n}"
        if n > 1:
            log.warning("photo %s: another photo has its id; kept as %s", base, photo_id)
        self._photo_ids.add(photo_id)
        return photo_id

    async def pose_of(self, shot: Shot, capture: Capture) -> PhotoPose | None:
        """The pose at the exposure.

        The autopilot's own record wins when the exposure is its trigger: AP_Camera writes
        CAMERA_FEEDBACK at the shutter from the EKF's position and attitude at that very
        instant, closer than the agent can get by interpolating 10 Hz streams that reach it
        late. Interpolation (position from GLOBAL_POSITION_INT, attitude from ATTITUDE, by
        the flight controller's clock) is for a feedback without a position, and for a
        camera the agent fires itself (OpenCV), whose exposure is the agent's grab, some
        time after the autopilot's trigger."""
        if capture.exposed_at is None and shot.feedback_pose is not None:
            return shot.feedback_pose
        exposed = capture.exposed_at if capture.exposed_at is not None else shot.arrived
        clock = self.poses.clock
        if not clock.synced:
            return None
        instant = clock.to_fcu(exposed)
        deadline = self._monotonic() + POSE_WAIT_S
        while (latest := self.poses.latest_time()) is None or latest < instant:
            if self._monotonic() >= deadline:
                break
            await asyncio.sleep(POSE_POLL_S)
        pose = self.poses.at(instant)
        if pose is None:
            return None
        utc = (
            shot.utc if capture.exposed_at is None else self._wall() - (self._monotonic() - exposed)
        )
        home = self._home_msl
        return PhotoPose(
            lat=pose.lat,
            lon=pose.lon,
            alt_msl=pose.alt_msl,
            alt_rel=pose.alt_msl - home if home is not None else 0.0,
            roll=_degrees(math.degrees(pose.roll), 180.0),
            pitch=max(-90.0, min(90.0, math.degrees(pose.pitch))),
            yaw=math.degrees(pose.yaw) % 360.0,
            time=utc,
        )


def _euler(q: Any) -> tuple[float, float, float]:
    """Roll, pitch and yaw (radians) of a MAVLink quaternion (w, x, y, z; body to NED)."""
    w, x, y, z = (float(v) for v in q)
    roll = math.atan2(2.0 * (w * x + y * z), 1.0 - 2.0 * (x * x + y * y))
    pitch = math.asin(max(-1.0, min(1.0, 2.0 * (w * y - z * x))))
    yaw = math.atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))
    return roll, pitch, yaw


def _degrees(value: float, half_turn: float) -> float:
    """An angle into [-half_turn, half_turn]."""
    return (value + half_turn) % (2.0 * half_turn) - half_turn
