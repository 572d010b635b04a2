"""Per-connection telemetry schedule, in wall-clock seconds.

Rates are wall-clock so a speed-up does not flood the link; what each message says is
the sim state at the moment it is sent.
"""

from __future__ import annotations

from collections.abc import Mapping

MIN_INTERVAL_S = 0.01  # 100 Hz at most per message


class StreamSchedule:
    """When each message id is next due on one connection."""

    def __init__(self, default_rates_hz: Mapping[int, float], now: float) -> None:
        self._defaults = {
            msg_id: 1.0 / rate for msg_id, rate in default_rates_hz.items() if rate > 0.0
        }
        self._intervals = dict(self._defaults)
        # everything is due at once on connect, so a new client learns the state quickly
        self._next_due = dict.fromkeys(self._intervals, now)

    def interval(self, msg_id: int) -> float | None:
        """Seconds between sends, or None if the message is not streamed."""
        return self._intervals.get(msg_id)

    def set_interval(self, msg_id: int, interval_s: float | None, now: float) -> None:
        """Stream ``msg_id`` every ``interval_s`` seconds; None stops it."""
        if interval_s is None:
            self._intervals.pop(msg_id, None)
            self._next_due.pop(msg_id, None)
            return
        self._intervals[msg_id] = max(interval_s, MIN_INTERVAL_S)
        self._next_due[msg_id] = now

    def reset_interval(self, msg_id: int, now: float) -> None:
        """Back to the default rate (or off, for a message not streamed by default)."""
        self.set_interval(msg_id, self._defaults.get(msg_id), now)

    def send_soon(self, msg_id: int, now: float) -> None:
        """Bring a streamed message forward to the next tick (e.g. HEARTBEAT on a mode change)."""
        if msg_id in self._next_due:
            self._next_due[msg_id] = min(self._next_due[msg_id], now)

    def due(self, now: float) -> list[int]:
        """Ids due at ``now``, in a stable order; each is rescheduled one interval on."""
        ready: list[int] = []
        for msg_id, due_at in self._next_due.items():
            if due_at > now:
                continue
            ready.append(msg_id)
            interval = self._intervals[msg_id]
            following = due_at + interval
            # after a stall, resume the rhythm from now rather than sending a burst
            self._next_due[msg_id] = following if following > now else now + interval
        return ready
