"""One camera shutter, however many messages tell of it.

ArduPilot's AP_Camera tells of each shutter once, with CAMERA_FEEDBACK. PX4 tells of it
twice: its camera_trigger module's CAMERA_TRIGGER (``seq``, from 0; streamed to a GCS link
only when asked for with SET_MESSAGE_INTERVAL) and its camera_feedback module's
CAMERA_IMAGE_CAPTURED (``image_index``, the same number; streamed by default), which
follows within milliseconds. Both must not make two photos, nor may the first be missed
when the other never comes.

The two are matched by their index alone, never by time or place: the entry-and-exit
"trigger once" of a survey lane and the distance trigger fire within milliseconds at the
same spot, and both are photos. A second message of the same kind with an index already
seen is another shutter (a counter numbering two alike: counted, never merged away), and
an index seen longer ago than `MATCH_WINDOW_S` is a new one (the counter restarted with
the flight controller).
"""

from __future__ import annotations

from collections import Counter, OrderedDict
from typing import Any

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

# MAVLink camera components (a camera of the camera protocol, e.g. the one in PX4's
# Gazebo SITL) send CAMERA_IMAGE_CAPTURED of their own, numbered their own way: only the
# autopilot's (its camera_feedback module) tells of its triggers.
_CAMERA_COMPONENTS = range(mavlink2.MAV_COMP_ID_CAMERA, mavlink2.MAV_COMP_ID_CAMERA6 + 1)
MATCH_WINDOW_S = 10.0  # CAMERA_IMAGE_CAPTURED follows its CAMERA_TRIGGER within milliseconds
KEPT = 256  # the newest indexes remembered


def from_autopilot(message: Any) -> bool:
    """The message comes from the autopilot, not a camera component beside it."""
    return int(message.get_srcComponent()) not in _CAMERA_COMPONENTS


def captured_alt_rel(message: Any, home_msl: float | None) -> float:
    """Metres above home of a CAMERA_IMAGE_CAPTURED. PX4 fills its ``relative_alt`` with
    the distance to the ground (camera_feedback's ``ground_distance``: a rangefinder's,
    -1 m without one), not the height above home the field's name promises: the height
    is its ``alt`` (above mean sea level) less home's, known from GLOBAL_POSITION_INT."""
    if home_msl is not None:
        return float(message.alt) / 1000.0 - home_msl
    return float(message.relative_alt) / 1000.0


class ShutterMatcher:
    """Says whether a camera message tells of a shutter not told of yet."""

    def __init__(self) -> None:
        # index -> when it was first told of, and how many times by each kind of message
        self._seen: OrderedDict[int, tuple[float, Counter[str]]] = OrderedDict()
        self.repeats = 0  # messages that told of a shutter already counted

    def is_new(self, kind: str, index: int, now: float) -> bool:
        """``kind`` (the message's type) tells of shutter ``index`` at monotonic ``now``."""
        seen = self._seen.get(index)
        if seen is None or now - seen[0] > MATCH_WINDOW_S:
            self._seen.pop(index, None)
            self._seen[index] = (now, Counter({kind: 1}))
            while len(self._seen) > KEPT:
                self._seen.popitem(last=False)
            return True
        told = seen[1]
        # New when this kind has told of as many shutters with this index as any other
        # kind: the other kind's message for it has not come (yet, or at all).
        new = told[kind] >= max(told.values())
        told[kind] += 1
        if not new:
            self.repeats += 1
        return new
