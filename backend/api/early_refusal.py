"""Refusals made before a request's body is read: a client refused in a loop costs the hub
its headers, not its body and the whole route. So is one that would find its work's
queue full (the password checks, the area files' worker).

A rate limit checked in a route comes after FastAPI has read and decoded the body and
resolved the route's dependencies: an area import refused for its user's rate still had
its megabyte of JSON decoded on the event loop first, and 20 users importing in a loop
held `/health` at a p99 of 357 ms. The checks here run first, on what the headers say
(the caller's token, its address), and answer the same 429 the route would
(`Retry-After`, the same words); they only look, so the route still counts what it lets
through. The refusal goes out at once; the body is then read and dropped, never decoded.
"""

from __future__ import annotations

from collections.abc import Awaitable, Callable

from starlette.requests import HTTPConnection
from starlette.responses import JSONResponse
from starlette.types import ASGIApp, Receive, Scope, Send

from backend.api.deps import get_login_address_limiter, get_passwords
from backend.api.security import client_address, principal_of
from backend.auth.rate_limit import whole_seconds
from backend.errors import RateLimited
from backend.survey.deps import get_surveys

EarlyCheck = Callable[[HTTPConnection], Awaitable[None]]


async def _import_rate(connection: HTTPConnection) -> None:
    principal = await principal_of(connection)
    if principal is not None:  # no caller: the route answers 401 as usual
        surveys = get_surveys(connection)
        surveys.import_limiter.check(principal.name, "survey imports")
        surveys.planner.import_pool.check_room()  # its worker's queue is full


async def _login_rate(connection: HTTPConnection) -> None:
    get_login_address_limiter(connection).check(client_address(connection), "login attempts")
    get_passwords(connection).check_room()  # as many password checks as allowed are under way


def early_checks(api_prefix: str) -> dict[tuple[str, str], EarlyCheck]:
    """(method, path) -> its check: the routes whose refusals come in floods."""
    return {
        ("POST", f"{api_prefix}/surveys/import"): _import_rate,
        ("POST", f"{api_prefix}/auth/token"): _login_rate,
        ("POST", f"{api_prefix}/auth/login"): _login_rate,
    }


class EarlyRefusal:
    def __init__(self, app: ASGIApp, checks: dict[tuple[str, str], EarlyCheck]) -> None:
        self.app = app
        self.checks = checks

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        check = None
        if scope["type"] == "http":
            check = self.checks.get((scope["method"], scope["path"]))
        if check is not None:
            try:
                await check(HTTPConnection(scope))
            except RateLimited as refused:
                headers = {"Retry-After": str(whole_seconds(refused.retry_after_s))}
                answer = JSONResponse({"detail": refused.message}, 429, headers=headers)
                await answer(scope, receive, send)
                await _discard_body(receive)
                return
        await self.app(scope, receive, send)


async def _discard_body(receive: Receive) -> None:
    """Read what is left of a refused request's body, undecoded, so the client that is
    still sending it reads the answer rather than a reset connection. The outer
    middlewares bound it (its size, its rate); one that ends it ends the reading too."""
    try:
        while (await receive()).get("more_body", False):
            pass
    except Exception:  # a body too large or too slow: uvicorn closes the connection
        return
