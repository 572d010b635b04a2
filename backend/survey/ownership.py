"""Which hub drives each active survey, when several share one database.

A survey's progress is followed from the shared bus, so every hub could follow it; but
only one may act on it (drop a drone, offer a hand-over, store its state), or two hubs
would store two diverging stories. The hub that creates a survey claims it (a row in
the same compare-and-set table as the manual-control leases, keyed ``survey:<id>``)
and renews the claim on every tick; the others leave it alone. A hub that dies stops
renewing: once its claim has expired, another hub's next look takes the survey over
from its last stored state, and drives it from there.
"""

from __future__ import annotations

import asyncio
import logging
import time
from collections.abc import Callable

from sqlalchemy.exc import SQLAlchemyError

from backend.storage.claims import LeaseClaimStore

log = logging.getLogger(__name__)

# Long against the survey tick (1 s) and a slow database, short against a hand-over:
# the drones fly their missions on their own meanwhile.
SURVEY_CLAIM_TTL_S = 10.0
# How often a hub looks for surveys whose hub stopped renewing them.
ADOPT_EVERY_S = 3.0


class SurveyOwnership:
    def __init__(
        self,
        store: LeaseClaimStore,
        hub_id: str,
        ttl_s: float = SURVEY_CLAIM_TTL_S,
        clock: Callable[[], float] = time.time,
    ) -> None:
        self._store = store
        self.hub_id = hub_id
        self.ttl_s = ttl_s
        self._clock = clock
        self._looked_at = 0.0

    async def take(self, survey_id: str) -> str | None:
        """None if this hub drives the survey now (taken or renewed); else who does."""
        try:
            return await asyncio.to_thread(
                self._store.claim,
                f"survey:{survey_id}",
                self.hub_id,
                self.hub_id,
                self._clock(),
                self.ttl_s,
            )
        except SQLAlchemyError as error:
            # Unknown is not ours: acting on a survey another hub may drive is the
            # greater harm; the drones fly their missions on their own meanwhile.
            log.warning("survey %s: its claim cannot be checked now: %s", survey_id, error)
            return "unknown (database unavailable)"

    def time_to_adopt(self) -> bool:
        now = self._clock()
        if now - self._looked_at < ADOPT_EVERY_S:
            return False
        self._looked_at = now
        return True
