"""The hub's services, wired once per process (``start.py`` builds them, ``work.py``
runs their background work); the routes reach them through ``backend/api/deps.py``."""

from __future__ import annotations

import asyncio
from collections.abc import Callable, Collection, Coroutine
from dataclasses import dataclass, field
from typing import Any

import httpx
from sqlalchemy import Engine

from backend.audit import AuditEntry, AuditLog
from backend.audit_denials import DenialCoalescer
from backend.auth.accounts import Accounts
from backend.auth.password_work import PasswordWork
from backend.auth.rate_limit import RateLimiter
from backend.fleet.commands import CommandDispatcher
from backend.fleet.param_catalog import ParamCatalog
from backend.fleet.registry import FleetRegistry, VehicleRecord
from backend.hub.collaborators import CommandPath
from backend.imagery.mosaic.service import MosaicService
from backend.imagery.photos.ingest import PhotoIngest
from backend.manual_control.service import ManualControl
from backend.mapping.tiles import TileLibrary
from backend.realtime.bus import InProcessBus, Topic
from backend.realtime.collaborators import AgentConnection, ClientConnection
from backend.realtime.fleet_link import FleetLink
from backend.realtime.live_events import RecentEvents
from backend.realtime.nats_bus import NatsBus
from backend.realtime.routing import AgentRoutes
from backend.realtime.vehicle_fanout import VehicleFanout
from backend.safety.service import SafetyService
from backend.scans.feed import ScanSubscription
from backend.scans.obstacles import describe as describe_obstacle
from backend.scans.pointmap import MapObstacle
from backend.scans.service import ScanService
from backend.scans.views import obstacle_views, point_map_view, site_origin
from backend.settings import HubSettings
from backend.storage.logbook import Logbook
from backend.storage.records import StoredEvent
from backend.storage.repository import Repository
from backend.storage.spool import RowSpool
from backend.storage.writer import StorageWriter
from backend.survey.service import SurveyService
from backend.viz3d.mirror import SceneLayer
from backend.viz3d.replay import ReplayPanels
from backend.viz3d.scene import FleetScene
from backend.viz3d.server import VizServer
from backend.viz3d.viewers import Viewers
from protocol.messages import (
    MAX_MAP_POINTS_SENT,
    CloseCode,
    HubEventKind,
    MapLayer,
    MissionItem,
    ObstaclesUpdate,
    PointMapUpdate,
)

SEVERITY_INFO = 6  # MAV_SEVERITY_INFO: an obstacle found or gone


@dataclass
class Hub:
    settings: HubSettings
    engine: Engine
    repository: Repository
    registry: FleetRegistry
    bus: InProcessBus | NatsBus
    # What sending a command uses; the surveys and the routed commands send through it.
    commands: CommandPath
    dispatcher: CommandDispatcher
    writer: StorageWriter
    logbook: Logbook
    accounts: Accounts
    audit: AuditLog
    # Failed logins per (address, user name), and per address whatever the name.
    login_limiter: RateLimiter
    login_address_limiter: RateLimiter
    command_limiter: RateLimiter
    passwords: PasswordWork
    safety: SafetyService
    scans: ScanService
    # Audit and command-log rows waiting out a database outage.
    spool: RowSpool
    # The offline tile sets in the tiles folder.
    tiles: TileLibrary
    # ArduPilot's parameter metadata files (PX4 serves its own through the agent).
    param_catalog: ParamCatalog
    # Refused requests, one audit row per principal, route and reason per interval.
    denials: DenialCoalescer
    # Manual control: the leases (in memory only) and their life (backend/manual_control/).
    manual_control: ManualControl
    # Vehicle states to the client feeds, batched and encoded once per tick.
    fanout: VehicleFanout
    # Area surveys, which send their commands through ``commands``.
    surveys: SurveyService
    # The live orthomosaic of each survey's photos (backend/mosaic/).
    mosaic: MosaicService
    # Survey photos from the agents' uploads; each stored photo of a survey goes on to
    # the mosaic (``photos.sink``).
    photos: PhotoIngest
    # The newest live events, which a dashboard gets first when it connects.
    recent_events: RecentEvents = field(default_factory=RecentEvents)
    # Live agent connections by vehicle, so revoking a token can drop its connection.
    agent_sessions: dict[str, AgentConnection] = field(default_factory=dict)
    # Held while an agent's hello is judged against the one holding its vehicle id.
    agent_admissions: dict[str, asyncio.Lock] = field(default_factory=dict)
    # Live client feeds, so a revoked token or disabled user stops seeing the fleet.
    client_feeds: set[ClientConnection] = field(default_factory=set)
    # The 3D view: viser on loopback, and the client that passes its page on (None when
    # GCS_VIZ_ENABLED is false).
    viz: VizServer | None = None
    viz_http: httpx.AsyncClient | None = None
    scene: FleetScene | None = None
    replays: ReplayPanels | None = None
    viewers: Viewers | None = None
    # Several hubs (GCS_BUS_URL): the NATS link, and the routes to agents on other hubs.
    fleet_link: FleetLink | None = None
    # The features app.py wires onto the hub (backend/formation/): their long-running
    # work, run with the hub's, and their layers of the 3D view.
    background: list[Callable[[], Coroutine[Any, Any, None]]] = field(default_factory=list)
    scene_layers: list[tuple[str, SceneLayer]] = field(default_factory=list)

    @property
    def routes(self) -> AgentRoutes | None:
        return None if self.fleet_link is None else self.fleet_link.routes

    async def publish_state(self, record: VehicleRecord) -> None:
        await self.bus.publish(Topic.VEHICLE_STATE, record.id, record.summary())

    async def mission_known(self, vehicle_id: str, items: list[MissionItem]) -> None:
        """The mission a vehicle now has (items after home), as the hub uploaded or read
        it: the 3D view draws its path."""
        if self.scene is None:
            return
        record = self.registry.get(vehicle_id)
        home_alt = record.state.home_alt_msl if record.state else None
        await asyncio.to_thread(self.scene.show_mission, vehicle_id, items, home_alt)

    async def refresh_obstacles(self) -> list[MapObstacle]:
        """The point map's obstacles now, with lasting ids; the changes since the last
        look are published as events of the vehicle whose scan last went into the map,
        and the new list to the feeds that subscribed to the map's obstacles."""
        changes = await self.scans.refresh_obstacles()
        vehicle_id = self.scans.mapped_by
        if vehicle_id is not None:
            for change, obstacles in (("found", changes.appeared), ("gone", changes.gone)):
                for obstacle in obstacles:
                    text = describe_obstacle(obstacle, change)
                    await self.store_event(vehicle_id, "obstacle", text, severity=SEVERITY_INFO)
        if changes.appeared or changes.gone:
            update = self._obstacles_now(changes.current)
            await self.bus.publish(Topic.MAP, update.type, update)
        return changes.current

    def _obstacles_now(self, current: list[MapObstacle]) -> ObstaclesUpdate:
        site = self.scans.site
        return ObstaclesUpdate(site=site_origin(site), obstacles=obstacle_views(current, site))

    def scan_subscription(self) -> ScanSubscription:
        """A live feed's scan subscription (the feed's ``FeedServices`` asks for it)."""
        return ScanSubscription()

    async def map_now(self, layers: Collection[MapLayer]) -> list[PointMapUpdate | ObstaclesUpdate]:
        now: list[PointMapUpdate | ObstaclesUpdate] = []
        if "points" in layers:
            view = await asyncio.to_thread(point_map_view, self.scans, MAX_MAP_POINTS_SENT)
            now.append(PointMapUpdate(map=view))
        if "obstacles" in layers:
            now.append(self._obstacles_now(self.scans.obstacles.current))
        return now

    async def store_event(
        self, vehicle_id: str, kind: HubEventKind, text: str, severity: int | None = None
    ) -> None:
        await self.commands.store_event(vehicle_id, kind, text, severity)

    async def publish_event(self, event: StoredEvent) -> None:
        await self.commands.publish_event(event)

    async def record(self, entry: AuditEntry) -> None:
        await self.commands.record(entry)

    async def record_denial(self, entry: AuditEntry, route: str, reason: str) -> None:
        """A refused request, coalesced with the same principal's same refusals
        (backend/audit_denials.py): a flood leaves a bounded trace."""
        await self.record_all(self.denials.admit(entry, route, reason))

    async def record_all(self, entries: list[AuditEntry]) -> None:
        for entry in entries:
            await self.record(entry)

    async def drop_user_feeds(self, token_id: int | None = None, user: str | None = None) -> None:
        """Close the live feeds of a revoked token, or of every session of a user."""
        for feed in list(self.client_feeds):
            if (token_id is not None and feed.token_id == token_id) or feed.user == user:
                await feed.close(CloseCode.UNAUTHORIZED, "session ended or revoked")

    async def drop_agent_token(self, token_id: int, vehicle_id: str) -> None:
        """A revoked agent token ends its live connection at once."""
        session = self.agent_sessions.get(vehicle_id)
        if session is not None and session.token_id == token_id:
            await session.close(CloseCode.UNAUTHORIZED, "agent token revoked")
