"""Every request that reaches a vehicle spends from its caller's budget.

A command, a parameter read or write, a mission upload, download, clear or a new
current item each make the agent and the flight controller work (a parameter list or a
mission is a long exchange on a slow radio link), so all of them share one per-user
budget: ``commands_per_second`` of the hub's settings. A group command spends one per
vehicle it reaches. Over budget the caller gets 429 with Retry-After.
"""

from __future__ import annotations

from typing import Annotated

from fastapi import Depends

from backend.api.deps import CommandLimiterDep
from backend.auth.policy import Principal
from backend.auth.rate_limit import RateLimiter

WHAT = "commands (each request that reaches a vehicle counts)"


class VehicleBudget:
    """The callers' shared budget of requests that reach a vehicle."""

    def __init__(self, limiter: RateLimiter) -> None:
        self._limiter = limiter

    def check(self, principal: Principal) -> None:
        """Raise RateLimited if the caller has no budget left (spends nothing)."""
        self._limiter.check(principal.name, WHAT)

    def spend(self, principal: Principal, vehicles: int = 1) -> None:
        """Refuse (RateLimited, 429) a caller with no budget left, else spend ``vehicles``.

        A call is accepted while any budget is left, so a fleet-wide RTL is never split."""
        self.check(principal)
        self._limiter.hit(principal.name, vehicles)


def get_vehicle_budget(limiter: CommandLimiterDep) -> VehicleBudget:
    return VehicleBudget(limiter)


VehicleBudgetDep = Annotated[VehicleBudget, Depends(get_vehicle_budget)]
