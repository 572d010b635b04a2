"""Which MISSION_ITEM_REACHED messages are news: a reached item counts once per pass.

PX4 sends MISSION_ITEM_REACHED when an item is reached and then ten more times at 1 Hz
(mavlink_mission.cpp, ``_reached_sent_count``); ArduPilot sends it once. A copy is the
same item again while the vehicle has not come back to it. A new pass of an item needs
MISSION_CURRENT to have gone back to it or before it since (a DO_JUMP, a restart, a
set-current, a new mission): before it at any time, or to it after having moved past it.
"""

from __future__ import annotations


class ReachedItems:
    """Feed it every MISSION_CURRENT and MISSION_ITEM_REACHED sequence number (as on
    the wire); ``reached`` says whether one is a new pass."""

    def __init__(self) -> None:
        self._last: int | None = None  # the item last reached, in this pass
        self._went_past = False  # MISSION_CURRENT has shown an item after it since

    def current(self, seq: int) -> None:
        last = self._last
        if last is None:
            return
        if seq > last:
            self._went_past = True
        elif seq < last or self._went_past:
            # back at the item or before it: reaching it again is a new pass. (Right after
            # a reach, MISSION_CURRENT may still name the item itself: that is no return.)
            self._last = None

    def reached(self, seq: int) -> bool:
        if seq == self._last:
            return False
        self._last = seq
        self._went_past = False
        return True
