"""The flight controller's texts, mission progress and shutters as numbered events."""

from __future__ import annotations

import logging
import time
from collections.abc import Callable

from protocol.messages import Event, EventKind, Photo, encode
from vehicle_agents.fcu.messages import MavMessage
from vehicle_agents.fcu.missions import mission_number
from vehicle_agents.hub.outbox import Outbox
from vehicle_agents.telemetry.mission_progress import ReachedItems
from vehicle_agents.telemetry.shutters import ShutterMatcher, captured_alt_rel, from_autopilot
from vehicle_agents.telemetry.statustext import StatusTextJoiner

log = logging.getLogger(__name__)
SEVERITY_NOTICE = 5  # MAV_SEVERITY_NOTICE: normal but significant

# CAMERA_FEEDBACK.flags: a photo (CAMERA_FEEDBACK_FLAGS; not a video or a bad capture).
CAMERA_FEEDBACK_PHOTO = 0
CAPTURE_FAILED = 0  # CAMERA_IMAGE_CAPTURED.capture_result: 1 success, 0 failure


class EventSource:
    """STATUSTEXTs and mission progress become numbered events for the hub's flight log:
    long texts joined from their chunks, each reached item once per pass."""

    def __init__(
        self,
        outbox: Outbox,
        autopilot: str,
        clock: Callable[[], float] = time.monotonic,
        *,
        has_image_source: bool = True,
    ) -> None:
        self._outbox = outbox
        # Without a camera source (--camera) a shutter is counted but has no image: SITL's
        # camera feedback, or a drone whose camera nobody told the agent of. Said once.
        self._has_image_source = has_image_source
        self._told_no_image = False
        self._autopilot = autopilot
        self._seq = 0
        self._clock = clock
        self._texts = StatusTextJoiner()
        self._reached = ReachedItems()
        # The latest GLOBAL_POSITION_INT (lat, lon, metres above home): where PX4's
        # CAMERA_TRIGGER, which carries no position, was taken.
        self._position: tuple[float, float, float] | None = None
        self._shutters = ShutterMatcher()  # PX4 tells of a shutter twice
        self._home_msl: float | None = None  # for CAMERA_IMAGE_CAPTURED's height

    def on_message(self, message: MavMessage) -> None:
        kind = message.get_type()
        now = self._clock()
        # An unfinished chunked text is let out on the next message after its wait
        # (heartbeats come every second), so no timer of its own is needed.
        texts = self._texts.add(message, now) if kind == "STATUSTEXT" else self._texts.due(now)
        for text in texts:
            self.emit("statustext", text.text, text.severity)
        if kind == "MISSION_CURRENT":
            self._reached.current(int(message.seq))
        elif kind == "MISSION_ITEM_REACHED" and self._reached.reached(int(message.seq)):
            number = mission_number(int(message.seq), self._autopilot)
            self.emit("mission", f"reached mission item {number}", None, mission_item=number)
        elif kind == "GLOBAL_POSITION_INT" and (message.lat or message.lon):
            self._position = (message.lat / 1e7, message.lon / 1e7, message.relative_alt / 1000.0)
            self._home_msl = message.alt / 1000.0 - message.relative_alt / 1000.0
        elif kind == "CAMERA_FEEDBACK" and int(message.flags) == CAMERA_FEEDBACK_PHOTO:
            # ArduPilot sends one per shutter release (AP_Camera), to every GCS link: the
            # photo's place for the survey's progress and the flight log.
            self._photo(
                Photo(
                    index=int(message.img_idx),
                    lat=message.lat / 1e7,
                    lon=message.lng / 1e7,
                    alt_rel=float(message.alt_rel),
                )
            )
        elif (
            kind == "CAMERA_IMAGE_CAPTURED"
            and from_autopilot(message)
            and int(message.capture_result) != CAPTURE_FAILED
        ):
            # PX4's camera_feedback sends one per shutter release, to every GCS link, with
            # where it was; its CAMERA_TRIGGER (the same index) may have come first.
            index = int(message.image_index)
            if (message.lat or message.lon) and self._shutters.is_new(kind, index, now):
                self._photo(
                    Photo(
                        index=index,
                        lat=message.lat / 1e7,
                        lon=message.lon / 1e7,
                        alt_rel=captured_alt_rel(message, self._home_msl),
                    )
                )
        elif kind == "CAMERA_TRIGGER" and self._position is not None:
            # PX4's camera_trigger sends one per shutter release (where the agent asks for
            # it), without a position: the latest one the autopilot streamed (a tenth of
            # a second old at 10 Hz).
            index = int(message.seq)
            if self._shutters.is_new(kind, index, now):
                lat, lon, alt_rel = self._position
                self._photo(Photo(index=index, lat=lat, lon=lon, alt_rel=alt_rel))

    def _photo(self, photo: Photo) -> None:
        self.emit(
            "camera",
            f"photo {photo.index} at {photo.lat:.7f}, {photo.lon:.7f}, "
            f"{photo.alt_rel:.1f} m above home",
            None,
            photo=photo,
        )
        if not self._has_image_source and not self._told_no_image:
            self._told_no_image = True
            text = (
                f"photo {photo.index}: the autopilot's camera fired, but no image source is "
                "configured (--camera): shots are counted, no image is uploaded"
            )
            log.warning("%s", text)
            self.emit("upload", text, SEVERITY_NOTICE)

    def emit(
        self,
        kind: EventKind,
        text: str,
        severity: int | None,
        *,
        mission_item: int | None = None,
        photo: Photo | None = None,
    ) -> None:
        event = Event(
            seq=self._seq,
            time=time.time(),
            kind=kind,
            severity=severity,
            text=text,
            mission_item=mission_item,
            photo=photo,
        )
        self._outbox.put("event", self._seq, encode(event))
        self._seq += 1
