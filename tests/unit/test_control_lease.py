"""The manual-control lease: one pilot per vehicle, renewed by input, refused otherwise."""

from __future__ import annotations

import pytest

from backend.auth.policy import Role, user_principal
from backend.control.lease import LeaseBook, LeaseLimits, LeaseRefused
from backend.errors import Forbidden


class Clock:
    def __init__(self) -> None:
        self.now = 100.0

    def __call__(self) -> float:
        return self.now


ALICE = user_principal("alice", Role.OPERATOR, None, token_id=1)
BOB = user_principal("bob", Role.OPERATOR, None, token_id=2)
VERA = user_principal("vera", Role.VIEWER, None, token_id=3)
ADA = user_principal("ada", Role.ADMIN, None, token_id=4)


def book(clock: Clock) -> LeaseBook:
    return LeaseBook(LeaseLimits(expiry_s=2.0, max_rate_hz=100.0), clock=clock)


def test_one_pilot_per_vehicle_and_a_viewer_gets_none() -> None:
    leases = book(Clock())
    leases.acquire("copter-1", ALICE)
    with pytest.raises(LeaseRefused, match="flown by hand by alice"):
        leases.acquire("copter-1", BOB)
    with pytest.raises(Forbidden):
        leases.acquire("copter-2", VERA)
    leases.acquire("copter-2", BOB)  # another vehicle, another pilot


def test_input_without_the_lease_is_refused_and_counted() -> None:
    leases = book(Clock())
    with pytest.raises(LeaseRefused, match="does not hold"):
        leases.admit("copter-1", "alice", 0)
    leases.acquire("copter-1", ALICE)
    with pytest.raises(LeaseRefused):
        leases.admit("copter-1", "bob", 0)
    assert leases.refused.no_lease == 2


def test_old_sequence_numbers_and_floods_are_refused() -> None:
    clock = Clock()
    leases = book(clock)
    leases.acquire("copter-1", ALICE)
    leases.admit("copter-1", "alice", 5)
    clock.now += 0.04
    with pytest.raises(LeaseRefused, match="not newer"):
        leases.admit("copter-1", "alice", 5)
    leases.admit("copter-1", "alice", 6)
    clock.now += 0.001  # 1 ms after the last accepted frame: over 100 Hz
    with pytest.raises(LeaseRefused, match="faster than 100 Hz"):
        leases.admit("copter-1", "alice", 7)
    clock.now += 0.04
    leases.admit("copter-1", "alice", 7)
    assert (leases.refused.old_seq, leases.refused.too_fast) == (1, 1)


def test_a_lease_expires_without_input_and_input_renews_it() -> None:
    clock = Clock()
    leases = book(clock)
    leases.acquire("copter-1", ALICE)
    for seq in range(100):  # 4 s of input at 25 Hz keeps it
        clock.now += 0.04
        leases.admit("copter-1", "alice", seq)
    assert leases.holder("copter-1") is not None
    clock.now += 2.01
    assert leases.holder("copter-1") is None
    with pytest.raises(LeaseRefused):
        leases.admit("copter-1", "alice", 1000)
    leases.acquire("copter-1", BOB)  # free for the next pilot


def test_only_an_admin_revokes_and_only_the_holder_releases() -> None:
    leases = book(Clock())
    leases.acquire("copter-1", ALICE)
    with pytest.raises(LeaseRefused):
        leases.release("copter-1", BOB)
    with pytest.raises(Forbidden):
        leases.revoke("copter-1", BOB)
    revoked = leases.revoke("copter-1", ADA)
    assert revoked is not None
    assert revoked.holder == "alice"
    assert leases.holder("copter-1") is None


def test_a_fresh_book_holds_no_lease() -> None:
    # Leases live in memory only: after a hub restart none is silently active.
    assert book(Clock()).holder("copter-1") is None
