"""The lease claims that make a manual-control lease exclusive across hubs: a
compare-and-set on one row per vehicle, on SQLite and on the real PostgreSQL."""

from __future__ import annotations

import threading

from sqlalchemy import Engine

from backend.storage.claims import LeaseClaimStore
from backend.storage.database import migrate

TTL_S = 4.0


def test_a_claim_holds_until_it_expires_and_its_holder_renews_it_from_any_hub(
    engine: Engine,
) -> None:
    migrate(engine)
    store = LeaseClaimStore(engine)
    assert store.claim("v1", "pilot", "hub-a", 100.0, TTL_S) is None
    assert store.claim("v1", "admin", "hub-b", 101.0, TTL_S) == "pilot"
    # The holder renews it, whichever hub its input now arrives at.
    assert store.claim("v1", "pilot", "hub-b", 102.0, TTL_S) is None
    assert store.claim("v1", "admin", "hub-b", 105.5, TTL_S) == "pilot"
    # Unrenewed (its hub died), it lapses and another operator may take it.
    assert store.claim("v1", "admin", "hub-b", 106.5, TTL_S) is None
    assert store.holder("v1", 107.0) == "admin"
    store.release("v1", "pilot")  # not the holder's any more: nothing changes
    assert store.holder("v1", 107.0) == "admin"
    store.release("v1", "admin")
    assert store.holder("v1", 107.0) is None
    assert store.claim("v1", "pilot", "hub-a", 108.0, TTL_S) is None


def _race(store: LeaseClaimStore, vehicle: str) -> dict[str, str | None]:
    """Hubs a and b claim the vehicle for their own operators at the same instant."""
    start = threading.Barrier(2)
    answers: dict[str, str | None] = {}

    def claim(holder: str) -> None:
        start.wait()
        answers[holder] = store.claim(vehicle, holder, f"hub-{holder}", 100.0, TTL_S)

    threads = [threading.Thread(target=claim, args=(holder,)) for holder in ("a", "b")]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join(10)
    return answers


def test_of_two_hubs_claiming_at_once_exactly_one_wins(engine: Engine) -> None:
    migrate(engine)
    store = LeaseClaimStore(engine)
    for round_ in range(20):
        answers = _race(store, f"race_{round_}")
        winners = [holder for holder, other in answers.items() if other is None]
        assert len(winners) == 1, answers
        [loser] = set(answers) - set(winners)
        assert answers[loser] == winners[0]
