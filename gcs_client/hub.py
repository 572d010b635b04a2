"""The asynchronous client: one ``Hub`` per hub, used as an async context manager.

    async with Hub("http://127.0.0.1:8000", username="admin", password="...") as hub:
        for vehicle in await hub.vehicles.list():
            print(vehicle.id, vehicle.connected)
        await hub.vehicles.command("sim_1", "takeoff", altitude=10)
        async for vehicle in hub.telemetry():
            print(vehicle.id, vehicle.state)

Credentials: a token (an API token, which does not need renewing until it expires), or a
username and password, with which the client logs in through the OAuth2 password flow
(``POST /api/v1/auth/token``) and logs in again before the access token expires, and once
more on a 401 (a token revoked by a restart of the hub's secrets, say). The live feed does
the same when the hub closes it with 4401.
"""

from __future__ import annotations

import asyncio
import os
import time
import weakref
from collections.abc import AsyncIterator
from typing import Any, Protocol, TypeVar

import httpx
from pydantic import BaseModel

from gcs_client.errors import (
    MissingCredentials,
    Unauthorized,
    api_error,
)
from gcs_client.feed import FleetWatch, LiveFeed, feed_url
from gcs_client.models import (
    AccessToken,
    VehicleSummary,
)
from gcs_client.resources import Audit, Auth, Events, Fleet, Flights, Vehicles
from gcs_client.transport import bearer, unreachable, without_none

M = TypeVar("M", bound=BaseModel)

DEFAULT_URL = "http://127.0.0.1:8000"
# Log in again this long before the access token expires (or a fifth of its lifetime,
# if that is shorter), so that no request goes out with a token about to lapse.
REFRESH_MARGIN_S = 60.0


class Closable(Protocol):
    async def aclose(self) -> None: ...


class Hub:
    """An authenticated connection to one hub's REST API and live feed."""

    def __init__(
        self,
        url: str = DEFAULT_URL,
        *,
        username: str | None = None,
        password: str | None = None,
        token: str | None = None,
        timeout: float = 60.0,
        verify: bool | str = True,
    ) -> None:
        if token is None and not (username and password):
            raise MissingCredentials(
                "give a token, or a username and password, to log in to the hub"
            )
        self.url = url.rstrip("/")
        self._username = username
        self._password = password
        self._token = token
        self._renew_at: float | None = None  # monotonic; None: a token that is not renewed
        self._timeout = timeout
        self._verify = verify
        self._login_lock = asyncio.Lock()
        self._http: httpx.AsyncClient | None = None
        # Feeds and watches made by this Hub, closed with it (weakly: one the caller
        # has dropped and closed is not kept alive for this).
        self._open: weakref.WeakSet[Closable] = weakref.WeakSet()
        self.vehicles = Vehicles(self)
        self.fleet = Fleet(self)
        self.flights = Flights(self)
        self.events = Events(self)
        self.audit = Audit(self)
        self.auth = Auth(self)

    @classmethod
    def from_env(cls, **overrides: Any) -> Hub:
        """The hub and credentials the examples use: ``GCS_HUB`` (default
        http://127.0.0.1:8000), and ``GCS_TOKEN`` or ``GCS_USERNAME`` and ``GCS_PASSWORD``."""
        token = os.environ.get("GCS_TOKEN") or None
        username = os.environ.get("GCS_USERNAME") or None
        password = os.environ.get("GCS_PASSWORD") or None
        if token is None and not (username and password):
            raise MissingCredentials("set GCS_TOKEN, or GCS_USERNAME and GCS_PASSWORD, to log in")
        settings: dict[str, Any] = {
            "url": os.environ.get("GCS_HUB", DEFAULT_URL),
            "token": token,
            "username": None if token else username,
            "password": None if token else password,
        }
        settings.update(overrides)
        return cls(**settings)

    async def __aenter__(self) -> Hub:
        await self.open()
        return self

    async def __aexit__(self, *exc: object) -> None:
        await self.aclose()

    async def open(self) -> None:
        """Connect, and log in now when given a password, so a wrong one fails here."""
        self._http = httpx.AsyncClient(
            base_url=self.url, timeout=self._timeout, verify=self._verify
        )
        if self._token is None:
            try:
                await self.login()
            except BaseException:
                await self.aclose()
                raise

    def keep_open(self, closable: Closable) -> None:
        """Close ``closable`` (a feed, a watch) when this Hub closes."""
        self._open.add(closable)

    def release(self, closable: Closable) -> None:
        """Leave ``closable`` to its owner to close."""
        self._open.discard(closable)

    async def aclose(self) -> None:
        """Close every feed and watch this Hub made, then its HTTP connections."""
        for closable in list(self._open):
            await closable.aclose()
        if self._http is not None:
            await self._http.aclose()
            self._http = None

    @property
    def http(self) -> httpx.AsyncClient:
        if self._http is None:
            raise RuntimeError("use the Hub as `async with Hub(...) as hub:` (or await open())")
        return self._http

    # -- credentials ---------------------------------------------------------------------

    @property
    def can_log_in(self) -> bool:
        return bool(self._username and self._password)

    async def login(self) -> AccessToken:
        """A fresh access token for the username and password (OAuth2 password flow)."""
        if not self.can_log_in:
            raise MissingCredentials("this Hub was given a token, not a username and password")
        answer = await self._send(
            "POST",
            "/api/v1/auth/token",
            data={"username": self._username, "password": self._password},  # a form
        )
        issued = AccessToken.model_validate(answer.json())
        self._token = issued.access_token
        margin = min(REFRESH_MARGIN_S, issued.expires_in / 5)
        self._renew_at = time.monotonic() + issued.expires_in - margin
        return issued

    async def token(self) -> str:
        """The bearer token to send now: logged in again first if it is about to expire."""
        async with self._login_lock:
            if self._token is None or (
                self._renew_at is not None and time.monotonic() >= self._renew_at
            ):
                await self.login()
        assert self._token is not None
        return self._token

    async def renew_after_refusal(self, refused: str) -> bool:
        """The hub refused the token ``refused``: log in again if we can (unless another
        task already has). False when there is no password to log in with."""
        if not self.can_log_in:
            return False
        async with self._login_lock:
            if self._token == refused:
                await self.login()
        return True

    # -- requests ------------------------------------------------------------------------

    async def _send(self, method: str, path: str, **kwargs: Any) -> httpx.Response:
        """One request, unauthenticated; an error answer or no answer raises."""
        try:
            answer = await self.http.request(method, path, **kwargs)
        except httpx.TransportError as error:
            raise unreachable(self.url, error) from None
        if not answer.is_success:
            raise api_error(answer)
        return answer

    async def request(self, method: str, path: str, **kwargs: Any) -> httpx.Response:
        """Any route of the REST API (``path`` from /api/v1/...), with the bearer token;
        an error answer raises its ``ApiError``. For routes this client has no method for."""
        token = await self.token()
        try:
            return await self._send(method, path, headers=bearer(token), **kwargs)
        except Unauthorized:
            if not await self.renew_after_refusal(token):
                raise
            return await self._send(method, path, headers=bearer(await self.token()), **kwargs)

    async def get_model(self, model: type[M], path: str, **params: Any) -> M:
        answer = await self.request("GET", path, params=without_none(params))
        return model.model_validate(answer.json())

    # -- the live feed -------------------------------------------------------------------

    def feed(self, *, reconnect: bool = True, resume_events: bool = True) -> LiveFeed:
        """Every message of the live feed, typed (``models.FeedMessage``), across
        reconnects. After a reconnect the hub sends a fresh ``fleet`` snapshot (the state
        of every vehicle now), and with ``resume_events`` the client first yields, as an
        ``events`` batch, what the flight log stored while it was away."""
        return LiveFeed(self, reconnect=reconnect, resume_events=resume_events)

    async def telemetry(self, *, reconnect: bool = True) -> AsyncIterator[VehicleSummary]:
        """Each vehicle's state as it changes: every vehicle of the snapshot first, then
        one ``VehicleSummary`` per update, with what an update leaves out filled in."""
        async with self.watch(reconnect=reconnect) as fleet:
            async for vehicle in fleet.updates():
                yield vehicle

    def watch(self, *, reconnect: bool = True) -> FleetWatch:
        """The fleet as the feed shows it, kept up to date: ``fleet.state(id)``,
        ``await fleet.wait_until(condition, timeout_s, what)``."""
        return FleetWatch(self, self.feed(reconnect=reconnect))

    @property
    def feed_url(self) -> str:
        return feed_url(self.url)
