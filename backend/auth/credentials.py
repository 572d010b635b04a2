"""Where a connection presents its credentials, and whose they are.

The REST routes (``backend.api.security``) and the dashboards' live feed
(``backend.realtime.client_feed``) read them the same way: a bearer token in the
Authorization header, else the dashboard's session cookie. A connection is anything with
headers and cookies (Starlette's requests and WebSockets are), so this knows nothing of
HTTP and both layers may import it.
"""

from __future__ import annotations

import asyncio
from collections.abc import Mapping
from typing import Protocol

from backend.auth.accounts import Accounts
from backend.auth.policy import Principal

SESSION_COOKIE = "gcs_session"


class Presenting(Protocol):
    """A connection as far as its credentials go."""

    @property
    def headers(self) -> Mapping[str, str]: ...

    @property
    def cookies(self) -> Mapping[str, str]: ...


def bearer_token(header: str | None) -> str | None:
    """The token of an ``Authorization: Bearer <token>`` header, if that is what it is."""
    if header is None:
        return None
    scheme, _, token = header.partition(" ")
    return token.strip() if scheme.lower() == "bearer" and token.strip() else None


def presented_token(connection: Presenting) -> str | None:
    """A bearer token from the Authorization header, else the dashboard's session cookie."""
    header = connection.headers.get("authorization")
    if header:
        return bearer_token(header)
    return connection.cookies.get(SESSION_COOKIE)


async def presented_principal(connection: Presenting, accounts: Accounts) -> Principal | None:
    token = presented_token(connection)
    if token is None:
        return None
    # One resolver for every token: an agent may use the REST routes that name its
    # permission (a .tlog upload) with whatever token it was enrolled or provisioned with.
    return await asyncio.to_thread(accounts.resolve_token, token)
