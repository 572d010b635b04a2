"""The principal cache's ages, expiry and revocation, on an injected clock."""

from __future__ import annotations

from backend.auth.policy import Role, agent_principal, user_principal
from backend.auth.principal_cache import PrincipalCache


class Clock:
    def __init__(self) -> None:
        self.now = 1000.0

    def __call__(self) -> float:
        return self.now


def test_fresh_then_only_during_an_outage_then_gone() -> None:
    clock = Clock()
    cache = PrincipalCache(fresh_s=10, outage_s=60, clock=clock, wall_clock=clock)
    olivia = user_principal("olivia", Role.OPERATOR, None, 7)
    cache.put("k", olivia, cache.generation)
    assert cache.fresh("k") == olivia
    clock.now += 11
    assert cache.fresh("k") is None  # ask the database again
    assert cache.during_outage("k") == olivia  # unless it cannot answer
    clock.now += 50
    assert cache.during_outage("k") is None


def test_a_token_expiry_holds_in_the_cache() -> None:
    clock = Clock()
    cache = PrincipalCache(fresh_s=10, outage_s=60, clock=clock, wall_clock=clock)
    cache.put("k", user_principal("olivia", Role.OPERATOR, None, 7, clock.now + 2), 0)
    clock.now += 3
    assert cache.during_outage("k") is None


def test_a_revocation_forgets_what_it_concerns_and_wins_a_race_with_a_look_up() -> None:
    cache = PrincipalCache(fresh_s=10, outage_s=60)
    olivia = user_principal("olivia", Role.OPERATOR, None, 7)
    agent = agent_principal("v1", 7)  # same id, another table
    cache.put("user", olivia, cache.generation)
    cache.put("agent", agent, cache.generation)
    looked_up_before = cache.generation
    cache.revoke(lambda who: not who.is_agent and who.token_id == 7)
    assert cache.fresh("user") is None
    assert cache.fresh("agent") == agent
    # A look-up that began before the revocation must not put the old answer back.
    cache.put("user", olivia, looked_up_before)
    assert cache.during_outage("user") is None
