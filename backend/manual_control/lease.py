"""The manual-control lease: one pilot per vehicle, renewed by the input stream.

Pure bookkeeping with an injected clock; the live feed applies it and audits the
changes. The hub forwards a manual-input frame only when ``admit`` says so: the lease
holder's own frame, newer than the last (newest wins); the relay caps the rate.
Leases live only in memory, so a hub restart leaves none active; the audit log tells
the restarted hub which were open, and it reports those as revoked
(backend/manual_control/service.py).
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

from backend.auth.policy import Permission, Principal, authorize
from backend.errors import Forbidden
from protocol.messages import LeaseState, ParamFix

if TYPE_CHECKING:
    from backend.manual_control.claims import LeaseClaims


@dataclass(frozen=True)
class LeaseLimits:
    """How long a lease lasts without input, and how fast input may come."""

    expiry_s: float = 2.0
    max_rate_hz: float = 100.0


class LeaseRefused(Forbidden):
    """The lease (or a frame under it) was refused; the message says why, and ``fix``
    the parameter change that would lift a refusal the vehicle's setup causes."""

    def __init__(self, message: str, fix: ParamFix | None = None) -> None:
        super().__init__(message)
        self.fix = fix


@dataclass
class Lease:
    vehicle_id: str
    holder: str
    token_id: int | None
    expires_at: float  # on the book's clock
    last_seq: int = -1
    last_input_at: float | None = None
    # The agent is still checking the autopilot and entering the pilot mode: the lease
    # is reserved (a second operator is refused) but does not expire meanwhile.
    starting: bool = False
    # A mission was flying when the lease began: this mode resumes it.
    resume_mode: str | None = None
    # Whom the lease was granted to: the hub's own stop at its end is sent in their name
    # (an agent on another hub takes only commands that name a user).
    principal: Principal | None = field(default=None, compare=False, repr=False)


@dataclass
class RefusalCounts:
    """Frames refused, by reason; never forwarded."""

    no_lease: int = 0
    old_seq: int = 0
    too_fast: int = 0

    def total(self) -> int:
        return self.no_lease + self.old_seq + self.too_fast


@dataclass
class LeaseBook:
    limits: LeaseLimits = field(default_factory=LeaseLimits)
    clock: Callable[[], float] = time.monotonic
    refused: RefusalCounts = field(default_factory=RefusalCounts)
    # The last lease state said of each vehicle, for dashboards that connect later.
    last_states: dict[str, LeaseState] = field(default_factory=dict)
    # Several hubs: the claims in the shared database that make a lease exclusive
    # across them (backend/manual_control/claims.py); None for a hub alone.
    claims: LeaseClaims | None = None
    _leases: dict[str, Lease] = field(default_factory=dict)

    def holder(self, vehicle_id: str) -> Lease | None:
        lease = self._leases.get(vehicle_id)
        if lease is not None and not lease.starting and self.clock() >= lease.expires_at:
            return None  # expired: expired() takes it away and the hub says so
        return lease

    def expired(self) -> list[Lease]:
        """Take away the leases whose input stopped renewing them."""
        now = self.clock()
        gone = [
            lease
            for lease in self._leases.values()
            if not lease.starting and now >= lease.expires_at
        ]
        for lease in gone:
            del self._leases[lease.vehicle_id]
        return gone

    def current(self) -> list[Lease]:
        return [lease for v in list(self._leases) if (lease := self.holder(v)) is not None]

    def started(self, lease: Lease) -> None:
        """The agent opened browser control: input now renews the lease."""
        lease.starting = False
        lease.expires_at = self.clock() + self.limits.expiry_s

    def cancel(self, lease: Lease) -> None:
        """The agent refused to open browser control: the reservation goes."""
        if self._leases.get(lease.vehicle_id) is lease:
            del self._leases[lease.vehicle_id]

    def acquire(self, vehicle_id: str, principal: Principal) -> Lease:
        """Grant the lease to an operator; the holder asking again just renews it."""
        authorize(principal, Permission.COMMAND, vehicle_id)
        if principal.is_agent:
            raise LeaseRefused("an agent cannot fly a vehicle by hand")
        lease = self.holder(vehicle_id)
        if lease is not None and lease.holder != principal.name:
            raise LeaseRefused(f"{vehicle_id} is flown by hand by {lease.holder}")
        if lease is None:
            lease = Lease(
                vehicle_id,
                principal.name,
                principal.token_id,
                0.0,
                starting=True,
                principal=principal,
            )
            self._leases[vehicle_id] = lease
        lease.expires_at = self.clock() + self.limits.expiry_s
        return lease

    def release(self, vehicle_id: str, principal: Principal) -> Lease:
        lease = self.holder(vehicle_id)
        if lease is None or lease.holder != principal.name:
            raise LeaseRefused(f"{principal.name} does not hold the lease of {vehicle_id}")
        del self._leases[vehicle_id]
        return lease

    def revoke(self, vehicle_id: str, principal: Principal | None = None) -> Lease | None:
        """End a lease whoever holds it: an admin (``principal``), or the hub itself
        (an RC mode change, the vehicle going offline) when ``principal`` is None."""
        if principal is not None:
            authorize(principal, Permission.ADMIN, vehicle_id)
        lease = self.holder(vehicle_id)
        self._leases.pop(vehicle_id, None)
        return lease

    def admit(self, vehicle_id: str, user: str, seq: int) -> Lease:
        """Whether a manual-input frame may be forwarded; renews the lease if so."""
        lease = self.holder(vehicle_id)
        if lease is None or lease.holder != user or lease.starting:
            self.refused.no_lease += 1
            raise LeaseRefused(f"{user} does not hold the manual-control lease of {vehicle_id}")
        if seq <= lease.last_seq:
            self.refused.old_seq += 1
            raise LeaseRefused(f"seq: {seq} is not newer than {lease.last_seq}")
        # Input faster than max_rate_hz is admitted here and collapses to its newest
        # frame in the relay (backend/manual_control/relay.py), which counts the rest
        # in refused.too_fast: a refusal here would keep a burst's oldest frame instead.
        now = self.clock()
        lease.last_seq = seq
        lease.last_input_at = now
        lease.expires_at = now + self.limits.expiry_s
        return lease
