"""Refusals coalesced per principal, route and reason: a flood writes at most two rows per
window, and the second carries the count."""

from __future__ import annotations

from backend.audit import AuditAction, AuditEntry
from backend.audit_denials import ANY_ROUTE, DenialCoalescer

ROUTE = "POST /api/v1/vehicles/{vehicle_id}/commands"
REASON = "needs 'command'"


class Clock:
    def __init__(self) -> None:
        self.now = 100.0

    def __call__(self) -> float:
        return self.now


def refusal(actor: str = "victor", target: str = "POST /api/v1/vehicles/v1/commands") -> AuditEntry:
    return AuditEntry(actor, "viewer", "127.0.0.1", AuditAction.DENIED, target, "denied", {})


def test_the_first_refusal_is_written_at_once_and_the_rest_counted() -> None:
    clock = Clock()
    denials = DenialCoalescer(60.0, clock=clock)
    assert denials.admit(refusal(), ROUTE, REASON) == [refusal()]
    for _ in range(500):
        assert denials.admit(refusal(), ROUTE, REASON) == []
    assert denials.closed() == []  # the window is still open
    clock.now += 60.0
    (count,) = denials.closed()
    assert count.actor == "victor"
    assert count.target == refusal().target
    assert count.detail == {"repeated": 500, "within_s": 60.0}
    assert denials.closed() == []  # written once


def test_a_refusal_after_the_window_writes_its_count_and_opens_a_new_one() -> None:
    clock = Clock()
    denials = DenialCoalescer(10.0, clock=clock)
    denials.admit(refusal(), ROUTE, REASON)
    denials.admit(refusal(), ROUTE, REASON)
    clock.now += 10.0
    count, fresh = denials.admit(refusal(), ROUTE, REASON)
    assert count.detail["repeated"] == 1
    assert fresh == refusal()


def test_a_lone_refusal_writes_no_count() -> None:
    clock = Clock()
    denials = DenialCoalescer(10.0, clock=clock)
    denials.admit(refusal(), ROUTE, REASON)
    clock.now += 11.0
    assert denials.closed() == []


def test_principals_routes_and_reasons_are_kept_apart() -> None:
    denials = DenialCoalescer(60.0, clock=Clock())
    assert denials.admit(refusal(), ROUTE, REASON)
    assert denials.admit(refusal("vera"), ROUTE, REASON)
    assert denials.admit(refusal(), "PUT /api/v1/safety/rails", REASON)
    assert denials.admit(refusal(), ROUTE, "another reason")
    assert not denials.admit(refusal(), ROUTE, REASON)


def test_the_keys_are_bounded_and_a_full_table_groups_a_principals_other_routes() -> None:
    denials = DenialCoalescer(60.0, max_keys=2, clock=Clock())
    denials.admit(refusal(), "A", REASON)
    denials.admit(refusal(), "B", REASON)
    assert denials.admit(refusal(), "C", REASON)  # the first on the shared key
    assert not denials.admit(refusal(), "D", REASON)  # counted with C under ANY_ROUTE
    (count,) = denials.closed(everything=True)
    assert count.detail["repeated"] == 1
    assert ANY_ROUTE == "*"
