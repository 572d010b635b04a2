"""The blocking client, for scripts that do not use asyncio: ``SyncHub`` has the methods of
``Hub`` without ``await``.

    with SyncHub("http://127.0.0.1:8000", username="admin", password="...") as hub:
        print([vehicle.id for vehicle in hub.vehicles.list()])

It runs a ``Hub`` on an event loop in a thread of its own and waits for each call, so the
two clients share one implementation (credentials, renewal, errors, the feed's
reconnects) rather than two that could drift apart, as httpx's two clients would.
"""

from __future__ import annotations

import asyncio
import threading
from collections.abc import AsyncIterator, Coroutine, Iterator, Mapping
from pathlib import Path
from typing import Any, TypeVar

import httpx

from gcs_client.hub import Hub
from gcs_client.models import (
    AccessToken,
    AuditPage,
    AuditRecord,
    Command,
    CommandResponse,
    EventPage,
    FeedMessage,
    FlightPage,
    GroupCommandResponse,
    Identity,
    IssuedApiToken,
    VehicleSummary,
)
from gcs_client.resources import ExportFormat

T = TypeVar("T")


class _Portal:
    """An event loop in a daemon thread, and a way to run a coroutine on it and wait."""

    def __init__(self) -> None:
        self.loop = asyncio.new_event_loop()
        self._thread = threading.Thread(target=self.loop.run_forever, daemon=True)
        self._thread.start()

    def run(self, coroutine: Coroutine[Any, Any, T]) -> T:
        return asyncio.run_coroutine_threadsafe(coroutine, self.loop).result()

    def iterate(self, iterator: AsyncIterator[T]) -> Iterator[T]:
        try:
            while True:
                try:
                    yield self.run(anext(iterator))  # type: ignore[arg-type]
                except StopAsyncIteration:
                    return
        finally:
            closing = getattr(iterator, "aclose", None)
            if closing is not None:
                self.run(closing())

    def stop(self) -> None:
        self.loop.call_soon_threadsafe(self.loop.stop)
        self._thread.join()
        self.loop.close()


class SyncHub:
    """``Hub``, blocking. Use it as a context manager (or call ``close()``)."""

    def __init__(self, url: str | None = None, **settings: Any) -> None:
        self._portal = _Portal()
        self._settings = settings if url is None else {"url": url, **settings}
        self._hub: Hub | None = None

    @classmethod
    def from_env(cls, **overrides: Any) -> SyncHub:
        """As ``Hub.from_env``: GCS_HUB, GCS_TOKEN or GCS_USERNAME and GCS_PASSWORD."""
        made = cls()
        try:
            made._hub = made._portal.run(_from_env(overrides))
        except BaseException:
            made._portal.stop()
            raise
        return made

    def __enter__(self) -> SyncHub:
        try:
            if self._hub is None:
                self._hub = self._portal.run(_make(self._settings))
            self._portal.run(self._hub.open())
        except BaseException:
            self._portal.stop()
            raise
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def close(self) -> None:
        if self._hub is not None:
            self._portal.run(self._hub.aclose())
            self._hub = None
        self._portal.stop()

    @property
    def hub(self) -> Hub:
        """The asynchronous client underneath."""
        if self._hub is None:
            raise RuntimeError("use the SyncHub as `with SyncHub(...) as hub:`")
        return self._hub

    def _run(self, coroutine: Coroutine[Any, Any, T]) -> T:
        return self._portal.run(coroutine)

    def login(self) -> AccessToken:
        return self._run(self.hub.login())

    def request(self, method: str, path: str, **kwargs: Any) -> httpx.Response:
        return self._run(self.hub.request(method, path, **kwargs))

    def feed(self, *, reconnect: bool = True, resume_events: bool = True) -> Iterator[FeedMessage]:
        return self._portal.iterate(
            aiter(self.hub.feed(reconnect=reconnect, resume_events=resume_events))
        )

    def telemetry(self, *, reconnect: bool = True) -> Iterator[VehicleSummary]:
        return self._portal.iterate(self.hub.telemetry(reconnect=reconnect))

    @property
    def vehicles(self) -> _Vehicles:
        return _Vehicles(self)

    @property
    def fleet(self) -> _Fleet:
        return _Fleet(self)

    @property
    def flights(self) -> _Flights:
        return _Flights(self)

    @property
    def events(self) -> _Events:
        return _Events(self)

    @property
    def audit(self) -> _Audit:
        return _Audit(self)

    @property
    def auth(self) -> _Auth:
        return _Auth(self)


async def _make(settings: Mapping[str, Any]) -> Hub:
    return Hub(**settings)  # made on the portal's loop, whose lock and client it uses


async def _from_env(overrides: Mapping[str, Any]) -> Hub:
    return Hub.from_env(**overrides)


class _Vehicles:
    def __init__(self, owner: SyncHub) -> None:
        self._owner = owner

    def list(self) -> list[VehicleSummary]:
        return self._owner._run(self._owner.hub.vehicles.list())

    def get(self, vehicle_id: str) -> VehicleSummary:
        return self._owner._run(self._owner.hub.vehicles.get(vehicle_id))

    def command(
        self,
        vehicle_id: str,
        command: str | Command | Mapping[str, Any],
        *,
        check: bool = True,
        **fields: Any,
    ) -> CommandResponse:
        commanding = self._owner.hub.vehicles.command(vehicle_id, command, check=check, **fields)
        return self._owner._run(commanding)


class _Fleet:
    def __init__(self, owner: SyncHub) -> None:
        self._owner = owner

    def command(
        self,
        command: str | Command | Mapping[str, Any],
        vehicle_ids: list[str] | None = None,
        **fields: Any,
    ) -> GroupCommandResponse:
        return self._owner._run(self._owner.hub.fleet.command(command, vehicle_ids, **fields))


class _Flights:
    def __init__(self, owner: SyncHub) -> None:
        self._owner = owner

    def list(self, vehicle_id: str | None = None, *, limit: int | None = None) -> FlightPage:
        return self._owner._run(self._owner.hub.flights.list(vehicle_id, limit=limit))

    def export(self, flight_id: int, fmt: ExportFormat, path: Path) -> Path:
        return self._owner._run(self._owner.hub.flights.export(flight_id, fmt, path))


class _Events:
    def __init__(self, owner: SyncHub) -> None:
        self._owner = owner

    def page(self, **filters: Any) -> EventPage:
        return self._owner._run(self._owner.hub.events.page(**filters))


class _Audit:
    def __init__(self, owner: SyncHub) -> None:
        self._owner = owner

    def page(self, **filters: Any) -> AuditPage:
        return self._owner._run(self._owner.hub.audit.page(**filters))

    def entries(
        self,
        *,
        action: str | None = None,
        actor: str | None = None,
        last: int | None = None,
        page_size: int = 100,
    ) -> Iterator[AuditRecord]:
        entries = self._owner.hub.audit.entries(
            action=action, actor=actor, last=last, page_size=page_size
        )
        return self._owner._portal.iterate(entries)


class _Auth:
    def __init__(self, owner: SyncHub) -> None:
        self._owner = owner

    def me(self) -> Identity:
        return self._owner._run(self._owner.hub.auth.me())

    def create_api_token(
        self, name: str, scopes: list[str] | None = None, *, expires_in_days: int | None = None
    ) -> IssuedApiToken:
        issuing = self._owner.hub.auth.create_api_token(
            name, scopes, expires_in_days=expires_in_days
        )
        return self._owner._run(issuing)
