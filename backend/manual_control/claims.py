"""The manual-control lease across several hubs: a claim in the shared database beside
each hub's own ``LeaseBook``.

The book stays the fast path (each stick frame is admitted in memory); the claim makes
the lease exclusive across hubs: a hub grants a lease only once its claim is taken, so
an operator on another hub is refused while the holder flies, whichever hub each is on.
The holder's hub renews its claims while the lease lives and deletes them when it ends;
a hub that dies stops renewing, and its claims expire after ``ttl_s``.
"""

from __future__ import annotations

import asyncio
import logging
import time
from collections.abc import Callable, Iterable

from sqlalchemy.exc import SQLAlchemyError

from backend.manual_control.lease import Lease, LeaseRefused
from backend.storage.claims import LeaseClaimStore

log = logging.getLogger(__name__)


class LeaseClaims:
    def __init__(
        self,
        store: LeaseClaimStore,
        hub_id: str,
        ttl_s: float,
        clock: Callable[[], float] = time.time,
    ) -> None:
        self._store = store
        self.hub_id = hub_id
        self.ttl_s = ttl_s
        # Renewed at a third of the time to live: two renewals may fail (a slow
        # database) before a live lease could lapse.
        self.renew_every_s = ttl_s / 3
        self._clock = clock
        self._renewed_at = 0.0

    async def claim(self, vehicle_id: str, holder: str) -> None:
        """Raises LeaseRefused if another operator holds the vehicle on any hub."""
        try:
            other = await asyncio.to_thread(
                self._store.claim, vehicle_id, holder, self.hub_id, self._clock(), self.ttl_s
            )
        except SQLAlchemyError as error:
            # Without the shared row no hub can tell who flies it: refuse, never guess.
            raise LeaseRefused(f"{vehicle_id}: the lease cannot be checked now ({error})") from None
        if other is not None:
            raise LeaseRefused(f"{vehicle_id} is flown by hand by {other}")

    async def release(self, vehicle_id: str, holder: str) -> None:
        try:
            await asyncio.to_thread(self._store.release, vehicle_id, holder)
        except SQLAlchemyError as error:
            log.warning("lease claim of %s not released (it expires): %s", vehicle_id, error)

    async def renew_due(self, leases: Iterable[Lease]) -> None:
        """Renew this hub's live claims if it is time; a claim another hub took meanwhile
        (ours lapsed) is logged, and the lease ends on its own expiry."""
        now = self._clock()
        if now - self._renewed_at < self.renew_every_s:
            return
        self._renewed_at = now
        for lease in list(leases):
            try:
                await self.claim(lease.vehicle_id, lease.holder)
            except LeaseRefused as refusal:
                log.error("lease of %s lost its claim: %s", lease.vehicle_id, refusal.message)
