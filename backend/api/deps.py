"""Typed dependencies for the routes: each hands a route only the service it uses.

The app's lifespan puts the started hub on ``app.state.hub`` (``backend/app.py``); the
getters here read one service from it, typed as that service or as a Protocol naming what
the route uses, so that no route imports the hub object (``backend.hub`` sits below the
API layer and is wired at start only; ``tests/unit/test_layers.py`` holds the rule). The
same pattern as the features' own ``deps.py`` (``backend/survey/deps.py``).
"""

from __future__ import annotations

from typing import Annotated, Any, Protocol

from fastapi import Depends
from starlette.requests import HTTPConnection

from backend.audit import AuditEntry, AuditLog
from backend.auth.accounts import Accounts
from backend.auth.password_work import PasswordWork
from backend.auth.rate_limit import RateLimiter
from backend.fleet.collaborators import CommandServices
from backend.fleet.registry import FleetRegistry
from backend.mapping.tiles import TileLibrary
from backend.realtime.collaborators import ClientConnection, FeedServices, GatewayServices
from backend.settings import HubSettings
from backend.storage.logbook import Logbook
from backend.storage.repository import Repository
from backend.storage.spool import RowSpool
from backend.storage.writer import StorageWriter
from backend.viz3d.gateway import VizServices
from backend.viz3d.viewers import Viewers
from protocol.messages import MissionItem


class AuditRecorder(Protocol):
    """The audit log as the routes write it: one entry, off the event loop."""

    async def record(self, entry: AuditEntry) -> None: ...


class DenialRecorder(Protocol):
    """Refused requests, coalesced per principal, route and reason (audit_denials.py)."""

    async def record_denial(self, entry: AuditEntry, route: str, reason: str) -> None: ...


class SessionEnder(Protocol):
    """Ends the live connections of a revoked token or a disabled user."""

    async def drop_user_feeds(
        self, token_id: int | None = None, user: str | None = None
    ) -> None: ...

    async def drop_agent_token(self, token_id: int, vehicle_id: str) -> None: ...


class MissionViews(Protocol):
    """Where a vehicle's known mission is drawn (the 3D view)."""

    async def mission_known(self, vehicle_id: str, items: list[MissionItem]) -> None: ...


def _wiring(connection: HTTPConnection) -> Any:
    """The started hub, untyped here on purpose: each getter below names its one service."""
    return connection.app.state.hub


def get_settings(connection: HTTPConnection) -> HubSettings:
    settings: HubSettings = _wiring(connection).settings
    return settings


def get_registry(connection: HTTPConnection) -> FleetRegistry:
    registry: FleetRegistry = _wiring(connection).registry
    return registry


def get_repository(connection: HTTPConnection) -> Repository:
    repository: Repository = _wiring(connection).repository
    return repository


def get_logbook(connection: HTTPConnection) -> Logbook:
    logbook: Logbook = _wiring(connection).logbook
    return logbook


def get_writer(connection: HTTPConnection) -> StorageWriter:
    writer: StorageWriter = _wiring(connection).writer
    return writer


def get_spool(connection: HTTPConnection) -> RowSpool:
    spool: RowSpool = _wiring(connection).spool
    return spool


def get_accounts(connection: HTTPConnection) -> Accounts:
    accounts: Accounts = _wiring(connection).accounts
    return accounts


def get_passwords(connection: HTTPConnection) -> PasswordWork:
    passwords: PasswordWork = _wiring(connection).passwords
    return passwords


def get_login_limiter(connection: HTTPConnection) -> RateLimiter:
    """Failed logins per (address, user name)."""
    limiter: RateLimiter = _wiring(connection).login_limiter
    return limiter


def get_login_address_limiter(connection: HTTPConnection) -> RateLimiter:
    """Failed logins per address, whatever the name."""
    limiter: RateLimiter = _wiring(connection).login_address_limiter
    return limiter


def get_command_limiter(connection: HTTPConnection) -> RateLimiter:
    """Each caller's budget of requests that reach a vehicle (vehicle_budget.py)."""
    limiter: RateLimiter = _wiring(connection).command_limiter
    return limiter


def get_tiles(connection: HTTPConnection) -> TileLibrary:
    tiles: TileLibrary = _wiring(connection).tiles
    return tiles


def get_viewers(connection: HTTPConnection) -> Viewers | None:
    """The 3D view's viewers (None when GCS_VIZ_ENABLED is false)."""
    viewers: Viewers | None = _wiring(connection).viewers
    return viewers


def get_client_feeds(connection: HTTPConnection) -> set[ClientConnection]:
    feeds: set[ClientConnection] = _wiring(connection).client_feeds
    return feeds


def get_audit_log(connection: HTTPConnection) -> AuditLog:
    """The audit log itself, to query (routes that record an entry take AuditDep)."""
    audit_log: AuditLog = _wiring(connection).audit
    return audit_log


def get_audit(connection: HTTPConnection) -> AuditRecorder:
    audit: AuditRecorder = _wiring(connection)
    return audit


def get_denials(connection: HTTPConnection) -> DenialRecorder:
    denials: DenialRecorder = _wiring(connection)
    return denials


def get_sessions(connection: HTTPConnection) -> SessionEnder:
    sessions: SessionEnder = _wiring(connection)
    return sessions


def get_mission_views(connection: HTTPConnection) -> MissionViews:
    views: MissionViews = _wiring(connection)
    return views


def get_command_services(connection: HTTPConnection) -> CommandServices:
    """What sending a command uses (the hub's ``CommandPath``)."""
    services: CommandServices = _wiring(connection).commands
    return services


def get_gateway_services(connection: HTTPConnection) -> GatewayServices:
    services: GatewayServices = _wiring(connection)
    return services


def get_feed_services(connection: HTTPConnection) -> FeedServices:
    services: FeedServices = _wiring(connection)
    return services


def get_viz_services(connection: HTTPConnection) -> VizServices:
    services: VizServices = _wiring(connection)
    return services


SettingsDep = Annotated[HubSettings, Depends(get_settings)]
RegistryDep = Annotated[FleetRegistry, Depends(get_registry)]
RepositoryDep = Annotated[Repository, Depends(get_repository)]
LogbookDep = Annotated[Logbook, Depends(get_logbook)]
WriterDep = Annotated[StorageWriter, Depends(get_writer)]
SpoolDep = Annotated[RowSpool, Depends(get_spool)]
AccountsDep = Annotated[Accounts, Depends(get_accounts)]
PasswordsDep = Annotated[PasswordWork, Depends(get_passwords)]
LoginLimiterDep = Annotated[RateLimiter, Depends(get_login_limiter)]
LoginAddressLimiterDep = Annotated[RateLimiter, Depends(get_login_address_limiter)]
CommandLimiterDep = Annotated[RateLimiter, Depends(get_command_limiter)]
TilesDep = Annotated[TileLibrary, Depends(get_tiles)]
ViewersDep = Annotated[Viewers | None, Depends(get_viewers)]
ClientFeedsDep = Annotated[set[ClientConnection], Depends(get_client_feeds)]
AuditLogDep = Annotated[AuditLog, Depends(get_audit_log)]
AuditDep = Annotated[AuditRecorder, Depends(get_audit)]
SessionsDep = Annotated[SessionEnder, Depends(get_sessions)]
MissionViewsDep = Annotated[MissionViews, Depends(get_mission_views)]
CommandServicesDep = Annotated[CommandServices, Depends(get_command_services)]
GatewayServicesDep = Annotated[GatewayServices, Depends(get_gateway_services)]
FeedServicesDep = Annotated[FeedServices, Depends(get_feed_services)]
VizServicesDep = Annotated[VizServices, Depends(get_viz_services)]
