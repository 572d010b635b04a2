"""Every request that reaches a vehicle spends from its caller's budget.

A command, a parameter read or write, a mission upload, download, clear or a new
current item each make the agent and the flight controller work (a parameter list or a
mission is a long exchange on a slow radio link), so all of them share one per-user
budget: ``commands_per_second`` of the hub's settings. A group command spends one per
vehicle it reaches. Over budget the caller gets 429 with Retry-After.
"""

from __future__ import annotations

from backend.auth.policy import Principal
from backend.hub import Hub

WHAT = "commands (each request that reaches a vehicle counts)"


def check_vehicle_budget(hub: Hub, principal: Principal) -> None:
    """Raise RateLimited if the caller has no budget left (spends nothing)."""
    hub.command_limiter.check(principal.name, WHAT)


def spend_vehicle_budget(hub: Hub, principal: Principal, vehicles: int = 1) -> None:
    """Refuse (RateLimited, 429) a caller with no budget left, else spend ``vehicles``.

    A call is accepted while any budget is left, so a fleet-wide RTL is never split."""
    check_vehicle_budget(hub, principal)
    hub.command_limiter.hit(principal.name, vehicles)
