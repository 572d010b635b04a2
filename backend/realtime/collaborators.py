"""What the live sessions and the hub need of each other, as structural types.

The hub (``backend.hub.services.Hub``) wires the sessions' collaborators once per process and sits
above this layer, so the sessions never import it: each declares here what it uses, and the
API layer hands them the hub, which provides all of it. The hub, in turn, keeps the live
sessions by the two connection types, so it never imports the sessions either.
"""

from __future__ import annotations

import asyncio
from collections.abc import Collection
from typing import Any, Protocol

from backend.audit import AuditEntry
from backend.auth.accounts import Accounts
from backend.fleet.commands import CommandDispatcher
from backend.fleet.registry import FleetRegistry, VehicleRecord
from backend.manual_control.service import ManualControl
from backend.realtime.bus import Bus, Subscription
from backend.realtime.live_events import RecentEvents
from backend.realtime.routing import AgentRoutes
from backend.realtime.vehicle_fanout import VehicleFanout
from backend.settings import HubSettings
from backend.storage.records import StoredEvent
from backend.storage.repository import Repository
from backend.storage.sequences import Gap, StreamKey
from protocol.messages import (
    HubEventKind,
    MapLayer,
    ObstaclesUpdate,
    PointMapUpdate,
)


class AgentConnection(Protocol):
    """An agent's live session, as the hub keeps it (to acknowledge, to revoke)."""

    token_id: int | None
    stream_id: str | None
    peer: str

    async def answers_within(self, timeout_s: float) -> bool: ...

    async def close(self, code: int, reason: str) -> None: ...

    def acknowledge(self, key: StreamKey, seq: int) -> None: ...

    def request_resend(self, gap: Gap) -> None: ...


class ScanIngest(Protocol):
    """Where an agent's binary scan frames go (backend.scans.service.ScanService)."""

    async def ingest(self, vehicle_id: str, stream_id: str, data: bytes) -> object:
        """Raises ValueError (with ``reason`` and ``message``) for a refused scan."""
        ...

    def source_reported(self, vehicle_id: str, source: str, counts: dict[str, int]) -> None:
        """The agent's word on its scan source (its parser's counts), for diagnostics."""
        ...


class ScanFeedSubscription(Subscription, Protocol):
    """A client feed's scans on the bus (backend.scans.feed.ScanSubscription): newest wins
    per vehicle, for the vehicles in ``vehicles``, which the feed edits as its client
    subscribes and unsubscribes."""

    vehicles: set[str]

    async def drain(self) -> list[Any]:
        """The scans waiting, one per vehicle, waiting until there is one."""
        ...


class ClientConnection(Protocol):
    """A dashboard's or integration's live feed, as the hub keeps it (to revoke)."""

    user: str
    token_id: int | None

    async def close(self, code: int, reason: str) -> None: ...


class FeedServices(Protocol):
    """What a client feed uses of the hub."""

    @property
    def settings(self) -> HubSettings: ...

    @property
    def registry(self) -> FleetRegistry: ...

    @property
    def bus(self) -> Bus: ...

    @property
    def fanout(self) -> VehicleFanout: ...

    @property
    def accounts(self) -> Accounts: ...

    @property
    def client_feeds(self) -> set[ClientConnection]: ...

    @property
    def manual_control(self) -> ManualControl: ...

    @property
    def dispatcher(self) -> CommandDispatcher: ...

    @property
    def recent_events(self) -> RecentEvents:
        """The newest live events, which a new feed sends first."""
        ...

    async def record(self, entry: AuditEntry) -> None: ...

    def scan_subscription(self) -> ScanFeedSubscription:
        """A new feed's scan subscription, for no vehicle yet."""
        ...

    async def store_event(
        self, vehicle_id: str, kind: HubEventKind, text: str, severity: int | None = None
    ) -> None: ...

    async def map_now(self, layers: Collection[MapLayer]) -> list[PointMapUpdate | ObstaclesUpdate]:
        """The site map's layers as they are now, for a feed that has just subscribed."""
        ...


class GatewayServices(Protocol):
    """What an agent's session uses of the hub."""

    @property
    def settings(self) -> HubSettings: ...

    @property
    def registry(self) -> FleetRegistry: ...

    @property
    def bus(self) -> Bus: ...

    @property
    def accounts(self) -> Accounts: ...

    @property
    def repository(self) -> Repository: ...

    @property
    def dispatcher(self) -> CommandDispatcher: ...

    @property
    def agent_sessions(self) -> dict[str, AgentConnection]: ...

    @property
    def agent_admissions(self) -> dict[str, asyncio.Lock]: ...

    @property
    def manual_control(self) -> ManualControl: ...

    @property
    def client_feeds(self) -> set[ClientConnection]: ...

    @property
    def scans(self) -> ScanIngest: ...

    @property
    def routes(self) -> AgentRoutes | None:
        """Several hubs: this hub answers for the agents connected to it."""
        ...

    async def record(self, entry: AuditEntry) -> None: ...

    async def store_event(
        self, vehicle_id: str, kind: HubEventKind, text: str, severity: int | None = None
    ) -> None: ...

    async def publish_state(self, record: VehicleRecord) -> None: ...

    async def publish_event(self, event: StoredEvent) -> None: ...
