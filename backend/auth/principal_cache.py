"""Who a token speaks for, remembered briefly, so that resolving a token does not need the
database on every request, and a database outage does not lock the operators out of LAND.

Two ages matter. An entry younger than ``fresh_s`` answers without asking the database;
that bounds how long a revocation made elsewhere (another hub on the same database) goes
unnoticed here. An entry younger than ``outage_s`` answers only while the database cannot
(nobody can revoke anything then either). A revocation through this hub clears the
entries it concerns at once, and a token's own expiry always holds.
"""

from __future__ import annotations

import threading
import time
from collections import OrderedDict
from collections.abc import Callable
from dataclasses import dataclass

from backend.auth.policy import Principal


@dataclass(frozen=True)
class _Entry:
    principal: Principal
    resolved_at: float  # monotonic


class PrincipalCache:
    def __init__(
        self,
        fresh_s: float,
        outage_s: float,
        max_entries: int = 10_000,
        clock: Callable[[], float] = time.monotonic,
        wall_clock: Callable[[], float] = time.time,
    ) -> None:
        self.fresh_s = fresh_s
        self.outage_s = max(outage_s, fresh_s)
        self.max_entries = max_entries
        self._clock = clock
        self._wall_clock = wall_clock
        # Resolving happens in worker threads; a lock keeps the dict and the generation
        # consistent with each other.
        self._lock = threading.Lock()
        self._entries: OrderedDict[str, _Entry] = OrderedDict()
        self._generation = 0

    @property
    def generation(self) -> int:
        """Changes on every revocation; read before a look-up, given back to ``put``."""
        return self._generation

    def fresh(self, key: str) -> Principal | None:
        return self._get(key, self.fresh_s)

    def during_outage(self, key: str) -> Principal | None:
        return self._get(key, self.outage_s)

    def put(self, key: str, principal: Principal, generation: int) -> None:
        """Remember a principal the database just gave, unless a revocation happened
        since the look-up began (it might have been this very token)."""
        with self._lock:
            if generation != self._generation:
                return
            self._entries[key] = _Entry(principal, self._clock())
            self._entries.move_to_end(key)
            while len(self._entries) > self.max_entries:
                self._entries.popitem(last=False)

    def forget(self, key: str) -> None:
        with self._lock:
            self._entries.pop(key, None)

    def revoke(self, concerned: Callable[[Principal], bool]) -> None:
        """Forget every principal a revocation concerns (a token, a user, a vehicle)."""
        with self._lock:
            self._generation += 1
            for key in [k for k, e in self._entries.items() if concerned(e.principal)]:
                del self._entries[key]

    def _get(self, key: str, max_age_s: float) -> Principal | None:
        with self._lock:
            entry = self._entries.get(key)
            if entry is None:
                return None
            expires_at = entry.principal.expires_at
            if expires_at is not None and expires_at <= self._wall_clock():
                del self._entries[key]
                return None
            if self._clock() - entry.resolved_at > max_age_s:
                return None
            return entry.principal
