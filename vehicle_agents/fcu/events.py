"""The flight controller link's ups and downs, as flight-log events.

A lost link is logged once when it goes and once when it comes back, not on every
failed reconnect attempt. The first "up" of a run is not an event: the vehicle's
appearance on the hub says as much.
"""

from __future__ import annotations

from collections.abc import Callable

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from protocol.messages import EventKind
from vehicle_agents.fcu.messages import LinkChange

EmitEvent = Callable[[EventKind, str, int | None], None]


class FcuLinkEvents:
    def __init__(self, emit: EmitEvent) -> None:
        self._emit = emit
        self._lost = False

    def on_link_change(self, change: LinkChange) -> None:
        if not change.up:
            self._lost = True
            self._emit(
                "link_down",
                f"flight controller link lost: {change.reason}; reconnecting",
                mavlink2.MAV_SEVERITY_CRITICAL,
            )
        elif self._lost:
            self._lost = False
            self._emit("link_up", "flight controller link restored", mavlink2.MAV_SEVERITY_NOTICE)
