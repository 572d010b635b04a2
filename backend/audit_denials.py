"""Refused requests, coalesced: a flood of them leaves a bounded trace that still names who
and what.

A refusal is worth a line in the audit log, but a client refused in a loop wrote one
permanent row per request (169 a second from one viewer). So refusals are grouped by a
key (who, which route template, which reason) into windows of ``interval_s``: the first
refusal of a window is written at once, as before, and the others are only counted; when
the window closes, one more row carries the count. Each key so writes at most two rows per
interval, however fast it is refused; the keys in memory are bounded too, and once they
are all taken a principal's further routes share one key of its own (route ``*``).
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, replace

from backend.audit import AuditEntry

# (actor, token id, route template, reason)
DenialKey = tuple[str, int | None, str, str]
ANY_ROUTE = "*"


@dataclass
class _Window:
    opened: float
    first: AuditEntry  # the refusal written when the window opened
    repeats: int = 0  # refusals since, not yet written


class DenialCoalescer:
    """Not thread-safe: the hub calls it from its event loop only."""

    def __init__(
        self,
        interval_s: float,
        max_keys: int = 1024,
        clock: Callable[[], float] = time.monotonic,
    ) -> None:
        self.interval_s = interval_s
        self.max_keys = max_keys
        self._clock = clock
        self._windows: dict[DenialKey, _Window] = {}

    def admit(self, entry: AuditEntry, route: str, reason: str) -> list[AuditEntry]:
        """The rows to write for this refusal now: none while its window is open, else
        the count of the window that just closed (if it had repeats) and this refusal."""
        key: DenialKey = (entry.actor, entry.token_id, route, reason)
        if key not in self._windows and len(self._windows) >= self.max_keys:
            key = (entry.actor, entry.token_id, ANY_ROUTE, reason)
        now = self._clock()
        window = self._windows.get(key)
        if window is not None and now - window.opened < self.interval_s:
            window.repeats += 1
            return []
        closed = [] if window is None else self._summaries([window])
        self._windows[key] = _Window(now, entry)
        return [*closed, entry]

    def closed(self, everything: bool = False) -> list[AuditEntry]:
        """The counts of every window past its interval (or of all, at shutdown), which
        are then forgotten: the rows a periodic flush writes."""
        now = self._clock()
        done = [
            key
            for key, window in self._windows.items()
            if everything or now - window.opened >= self.interval_s
        ]
        return self._summaries([self._windows.pop(key) for key in done])

    def _summaries(self, windows: list[_Window]) -> list[AuditEntry]:
        return [
            replace(
                window.first,
                detail={
                    **window.first.detail,
                    "repeated": window.repeats,
                    "within_s": self.interval_s,
                },
            )
            for window in windows
            if window.repeats > 0
        ]
