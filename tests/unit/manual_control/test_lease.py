"""The manual-control lease: one pilot per vehicle, renewed by input, refused otherwise."""

from __future__ import annotations

import json

import pytest

from backend.auth.policy import Principal, Role, user_principal
from backend.errors import Forbidden
from backend.manual_control.lease import Lease, LeaseBook, LeaseLimits, LeaseRefused
from backend.manual_control.service import leases_left_open
from backend.storage.models import AuditRow


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


def granted(leases: LeaseBook, vehicle_id: str, principal: Principal) -> Lease:
    """Acquired, and opened on the vehicle (the agent accepted manual_start)."""
    lease = leases.acquire(vehicle_id, principal)
    leases.started(lease)
    return lease


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
    lease = leases.acquire("copter-1", ALICE)
    with pytest.raises(LeaseRefused):  # still opening on the vehicle
        leases.admit("copter-1", "alice", 0)
    leases.started(lease)
    with pytest.raises(LeaseRefused):
        leases.admit("copter-1", "bob", 0)
    assert leases.refused.no_lease == 3


def test_old_sequence_numbers_are_refused() -> None:
    clock = Clock()
    leases = book(clock)
    granted(leases, "copter-1", ALICE)
    leases.admit("copter-1", "alice", 5)
    clock.now += 0.04
    with pytest.raises(LeaseRefused, match="not newer"):
        leases.admit("copter-1", "alice", 5)
    leases.admit("copter-1", "alice", 6)
    with pytest.raises(LeaseRefused, match="not newer"):
        leases.admit("copter-1", "alice", 2)
    # Floods are the relay's to collapse (tests/unit/manual_control/test_relay.py).
    assert leases.refused.old_seq == 2


def test_a_lease_expires_without_input_and_input_renews_it() -> None:
    clock = Clock()
    leases = book(clock)
    granted(leases, "copter-1", ALICE)
    for seq in range(100):  # 4 s of input at 25 Hz keeps it
        clock.now += 0.04
        leases.admit("copter-1", "alice", seq)
    assert leases.holder("copter-1") is not None
    assert leases.expired() == []
    clock.now += 2.01
    assert leases.holder("copter-1") is None
    with pytest.raises(LeaseRefused):
        leases.admit("copter-1", "alice", 1000)
    assert [lease.holder for lease in leases.expired()] == ["alice"]  # the hub says so
    assert leases.expired() == []  # once
    leases.acquire("copter-1", BOB)  # free for the next pilot


def test_a_lease_opening_on_the_vehicle_does_not_expire_and_a_refusal_frees_it() -> None:
    clock = Clock()
    leases = book(clock)
    lease = leases.acquire("copter-1", ALICE)
    clock.now += 30  # the agent reading the parameter table over a slow radio
    assert leases.expired() == []
    with pytest.raises(LeaseRefused, match="flown by hand by alice"):
        leases.acquire("copter-1", BOB)
    leases.cancel(lease)  # the autopilot would drop MANUAL_CONTROL: refused
    assert leases.holder("copter-1") is None
    leases.acquire("copter-1", BOB)


def test_only_an_admin_revokes_and_only_the_holder_releases() -> None:
    leases = book(Clock())
    granted(leases, "copter-1", ALICE)
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


def _row(target: str, actor: str, action: str, outcome: str = "ok") -> AuditRow:
    return AuditRow(
        target=target, actor=actor, outcome=outcome, detail=json.dumps({"action": action})
    )


def test_the_audit_log_tells_a_restarted_hub_which_leases_were_open() -> None:
    rows = [  # newest first
        _row("copter-1", "alice", "acquire"),
        _row("copter-2", "hub", "end"),
        _row("copter-2", "bob", "acquire"),
        _row("copter-3", "bob", "acquire", outcome="refused"),
        _row("copter-4", "alice", "release"),
        _row("copter-4", "alice", "acquire"),
        _row("copter-1", "alice", "release"),
    ]
    assert leases_left_open(rows) == {"copter-1": "alice"}
