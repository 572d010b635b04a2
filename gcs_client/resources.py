"""The hub's resources as the client's ``Hub`` offers them: ``hub.vehicles``, ``hub.fleet``,
``hub.flights``, ``hub.events``, ``hub.audit`` and ``hub.auth``, each a thin typed face of
its REST routes."""

from __future__ import annotations

from collections.abc import AsyncIterator, Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Any, Literal

import httpx
from pydantic import BaseModel, TypeAdapter, ValidationError

from gcs_client.errors import (
    CommandRefused,
    InvalidCommand,
    api_error,
)
from gcs_client.models import (
    COMMAND_ADAPTER,
    AuditPage,
    AuditRecord,
    Command,
    CommandResponse,
    EventPage,
    FlightPage,
    GroupCommandResponse,
    Identity,
    IssuedApiToken,
    VehicleSummary,
)
from gcs_client.transport import bearer, unreachable

if TYPE_CHECKING:
    from gcs_client.hub import Hub

ExportFormat = Literal["geojson", "csv", "tlog"]
VEHICLES_ADAPTER = TypeAdapter(list[VehicleSummary])


class Vehicles:
    def __init__(self, hub: Hub) -> None:
        self._hub = hub

    async def list(self) -> list[VehicleSummary]:
        answer = await self._hub.request("GET", "/api/v1/vehicles")
        return VEHICLES_ADAPTER.validate_python(answer.json())

    async def get(self, vehicle_id: str) -> VehicleSummary:
        return await self._hub.get_model(VehicleSummary, f"/api/v1/vehicles/{vehicle_id}")

    async def command(
        self,
        vehicle_id: str,
        command: str | Command | Mapping[str, Any],
        *,
        check: bool = True,
        **fields: Any,
    ) -> CommandResponse:
        """Send one command and wait for the flight controller's verdict: ``command`` is a
        name (``"takeoff"``, with its fields as keywords), a model (``TakeoffCommand``) or
        a dict. Raises ``CommandRefused`` unless it was accepted (``check=False``: return
        the answer whatever the verdict)."""
        body = command_body(command, fields)
        answer = await self._hub.request(
            "POST", f"/api/v1/vehicles/{vehicle_id}/commands", json=body
        )
        response = CommandResponse.model_validate(answer.json())
        if check and response.outcome.status != "accepted":
            raise CommandRefused(vehicle_id, str(body["name"]), response.outcome)
        return response


class Fleet:
    def __init__(self, hub: Hub) -> None:
        self._hub = hub

    async def command(
        self,
        command: str | Command | Mapping[str, Any],
        vehicle_ids: list[str] | None = None,
        **fields: Any,
    ) -> GroupCommandResponse:
        """One command to several vehicles at once (every connected one without
        ``vehicle_ids``), answered with a result per vehicle: check each; one vehicle
        refusing does not raise."""
        body = {"vehicle_ids": vehicle_ids, "command": command_body(command, fields)}
        answer = await self._hub.request("POST", "/api/v1/fleet/commands", json=body)
        return GroupCommandResponse.model_validate(answer.json())


class Flights:
    def __init__(self, hub: Hub) -> None:
        self._hub = hub

    async def list(self, vehicle_id: str | None = None, *, limit: int | None = None) -> FlightPage:
        """Flights (arm to disarm), newest first."""
        return await self._hub.get_model(
            FlightPage, "/api/v1/flights", vehicle_id=vehicle_id, limit=limit
        )

    async def export(self, flight_id: int, fmt: ExportFormat, path: Path) -> Path:
        """Download one flight as GeoJSON, CSV or a .tlog into ``path``, streamed: a long
        flight is never held in memory whole, here or in the hub."""
        route = f"/api/v1/flights/{flight_id}/export.{fmt}"
        token = await self._hub.token()
        try:
            async with self._hub.http.stream("GET", route, headers=bearer(token)) as answer:
                if not answer.is_success:
                    await answer.aread()
                    raise api_error(answer)
                with path.open("wb") as file:
                    async for chunk in answer.aiter_bytes():
                        file.write(chunk)
        except httpx.TransportError as error:
            raise unreachable(self._hub.url, error) from None
        return path


class Events:
    def __init__(self, hub: Hub) -> None:
        self._hub = hub

    async def page(
        self,
        *,
        vehicle_id: str | None = None,
        kind: str | None = None,
        start: float | None = None,
        end: float | None = None,
        before_id: int | None = None,
        limit: int = 100,
    ) -> EventPage:
        """The flight log's events, newest first; ``next_before_id`` pages on."""
        return await self._hub.get_model(
            EventPage,
            "/api/v1/events",
            vehicle_id=vehicle_id,
            kind=kind,
            start=start,
            end=end,
            before_id=before_id,
            limit=limit,
        )


class Audit:
    def __init__(self, hub: Hub) -> None:
        self._hub = hub

    async def page(
        self,
        *,
        action: str | None = None,
        actor: str | None = None,
        before_id: int | None = None,
        limit: int = 100,
    ) -> AuditPage:
        """One page of the audit log, newest first (needs the 'audit' permission)."""
        return await self._hub.get_model(
            AuditPage,
            "/api/v1/audit",
            action=action,
            actor=actor,
            before_id=before_id,
            limit=limit,
        )

    async def entries(
        self,
        *,
        action: str | None = None,
        actor: str | None = None,
        last: int | None = None,
        page_size: int = 100,
    ) -> AsyncIterator[AuditRecord]:
        """Entries newest first, page after page (following ``next_before_id``), up to
        ``last`` of them (all without it)."""
        shown = 0
        before_id: int | None = None
        while last is None or shown < last:
            size = page_size if last is None else min(page_size, last - shown)
            page = await self.page(action=action, actor=actor, before_id=before_id, limit=size)
            for entry in page.entries:
                yield entry
            shown += len(page.entries)
            if page.next_before_id is None:
                return
            before_id = page.next_before_id


class Auth:
    def __init__(self, hub: Hub) -> None:
        self._hub = hub

    async def me(self) -> Identity:
        return await self._hub.get_model(Identity, "/api/v1/auth/me")

    async def create_api_token(
        self, name: str, scopes: list[str] | None = None, *, expires_in_days: int | None = None
    ) -> IssuedApiToken:
        """A scoped API token for a script (shown once: store ``.token`` now)."""
        body: dict[str, Any] = {"name": name, "scopes": scopes}
        if expires_in_days is not None:
            body["expires_in_days"] = expires_in_days
        answer = await self._hub.request("POST", "/api/v1/auth/api-tokens", json=body)
        return IssuedApiToken.model_validate(answer.json())


def command_body(command: str | Command | Mapping[str, Any], fields: Mapping[str, Any]) -> Any:
    """The JSON of one command, checked against the generated models before it goes: a
    misspelt name fails here, naming the valid ones, rather than as a 422."""
    if isinstance(command, str):
        data: Any = {"name": command, **fields}
    elif isinstance(command, BaseModel):
        data = {**command.model_dump(by_alias=True, exclude_unset=True), **fields}
        data.setdefault("name", getattr(command, "name", None))
    else:
        data = {**command, **fields}
    try:
        parsed = COMMAND_ADAPTER.validate_python(data)
    except ValidationError as error:
        raise InvalidCommand(f"not a command the hub takes: {error}") from None
    # What was given, and the name: the hub fills in its own defaults.
    given = parsed.model_dump(mode="json", by_alias=True, exclude_unset=True)
    return {**given, "name": parsed.name}
