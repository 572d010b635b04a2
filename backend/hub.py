"""The hub's services, wired once per process; the API layer reaches them through this."""

from __future__ import annotations

import asyncio
import logging
import time
from collections.abc import Callable, Collection, Coroutine
from dataclasses import dataclass, field
from typing import Any

import httpx
from sqlalchemy import Engine
from sqlalchemy.exc import SQLAlchemyError

from backend.audit import AuditAction, AuditEntry, AuditLog
from backend.audit_denials import DenialCoalescer
from backend.auth.accounts import PROVISIONING, Accounts
from backend.auth.password_policy import password_problem
from backend.auth.password_work import PasswordWork
from backend.auth.policy import Principal
from backend.auth.principal_cache import PrincipalCache
from backend.auth.rate_limit import Limit, RateLimiter
from backend.errors import NotFound
from backend.fleet.command_service import carry_out_routed
from backend.fleet.commands import CommandDispatcher
from backend.fleet.param_catalog import ParamCatalog
from backend.fleet.registry import FleetRegistry, VehicleRecord
from backend.imagery.mosaic.service import MosaicService
from backend.imagery.photos.ingest import PhotoIngest
from backend.imagery.photos.partials import PartialLimits
from backend.imagery.photos.repository import PhotoRepository
from backend.imagery.sink import MosaicSink
from backend.manual_control.claims import LeaseClaims
from backend.manual_control.service import ManualControl
from backend.manual_control.store import LeaseClaimStore
from backend.mapping.tiles import TileLibrary
from backend.realtime.bus import InProcessBus, ReliableSubscription, Topic
from backend.realtime.collaborators import AgentConnection, ClientConnection
from backend.realtime.fleet_link import FleetLink
from backend.realtime.live_events import live_event
from backend.realtime.nats_bus import NatsBus
from backend.realtime.routing import AgentRoutes
from backend.realtime.vehicle_fanout import VehicleFanout
from backend.safety.rails_store import RailsRepository
from backend.safety.service import SafetyService
from backend.scans.feed import ScanSubscription
from backend.scans.obstacles import describe as describe_obstacle
from backend.scans.pointmap import MapObstacle
from backend.scans.repository import ScanRepository
from backend.scans.service import ScanService
from backend.scans.views import obstacle_views, point_map_view, site_origin
from backend.settings import HubSettings
from backend.storage.database import make_engine, migrate
from backend.storage.logbook import Logbook
from backend.storage.models import AuditRow, CommandRow
from backend.storage.records import StoredEvent
from backend.storage.repository import Repository
from backend.storage.retention import RetentionPolicy
from backend.storage.sequences import Gap, StreamKey
from backend.storage.spool import RowSpool
from backend.storage.writer import StorageWriter
from backend.survey.ownership import SurveyOwnership
from backend.survey.repository import SurveyRepository
from backend.survey.service import SurveyService
from backend.viz3d.frame import SceneFrame, parse_origin
from backend.viz3d.mirror import SceneLayer, SceneMirror
from backend.viz3d.replay import ReplayPanels
from backend.viz3d.scene import FleetScene
from backend.viz3d.server import VizServer
from backend.viz3d.viewers import Viewers
from protocol.messages import (
    MAX_MAP_POINTS_SENT,
    CloseCode,
    CommandOutcome,
    HubEventKind,
    MapLayer,
    MissionItem,
    ObstaclesUpdate,
    PointMapUpdate,
)
from protocol.routing import RoutedCommand, RoutedSender

SEVERITY_INFO = 6  # MAV_SEVERITY_INFO: an obstacle found or gone
POINT_MAP_PUBLISH_S = 2.0
log = logging.getLogger(__name__)


@dataclass
class Hub:
    settings: HubSettings
    engine: Engine
    repository: Repository
    registry: FleetRegistry
    bus: InProcessBus | NatsBus
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
    # Live agent connections by vehicle, so revoking a token can drop its connection.
    agent_sessions: dict[str, AgentConnection] = field(default_factory=dict)
    # Held while an agent's hello is judged against the one holding its vehicle id.
    agent_admissions: dict[str, asyncio.Lock] = field(default_factory=dict)
    # Live client feeds, so a revoked token or disabled user stops seeing the fleet.
    client_feeds: set[ClientConnection] = field(default_factory=set)
    # Manual control: the leases (in memory only) and their life (backend/manual_control/).
    manual_control: ManualControl = field(init=False)
    # The 3D view: viser on loopback, and the client that passes its page on (None when
    # GCS_VIZ_ENABLED is false).
    viz: VizServer | None = None
    viz_http: httpx.AsyncClient | None = None
    scene: FleetScene | None = None
    replays: ReplayPanels | None = None
    viewers: Viewers | None = None
    # Vehicle states to the client feeds, batched and encoded once per tick.
    fanout: VehicleFanout = field(init=False)
    # Several hubs (GCS_BUS_URL): the NATS link, and the routes to agents on other hubs.
    fleet_link: FleetLink | None = None
    # Area surveys: created in start(), as they send commands through the hub itself.
    surveys: SurveyService = field(init=False)
    # The live orthomosaic of each survey's photos (backend/imagery/mosaic/).
    mosaic: MosaicService = field(init=False)
    # Survey photos from the agents' uploads; each stored photo of a survey goes on to
    # the mosaic (``photos.sink``).
    photos: PhotoIngest = field(init=False)
    # The features app.py wires onto the hub (backend/formation/): their long-running
    # work, run with the hub's, and their layers of the 3D view.
    background: list[Callable[[], Coroutine[Any, Any, None]]] = field(default_factory=list)
    scene_layers: list[tuple[str, SceneLayer]] = field(default_factory=list)

    @classmethod
    async def start(cls, settings: HubSettings) -> Hub:
        """Open the store (migrating it) and load the vehicles it knows."""
        engine = make_engine(settings.sqlalchemy_url)
        await asyncio.to_thread(migrate, engine)
        repository = Repository(engine)
        registry = FleetRegistry()
        registry.load(await asyncio.to_thread(repository.vehicles))
        fleet_link = None
        bus: InProcessBus | NatsBus = InProcessBus()
        if settings.bus_url is not None:
            fleet_link = await FleetLink.connect(settings, registry)
            bus = fleet_link.bus
        stored = ReliableSubscription(settings.telemetry_queue_limit)
        bus.subscribe(Topic.STORAGE, stored)
        logbook = Logbook(engine)
        writer = await asyncio.to_thread(
            StorageWriter,
            repository,
            logbook,
            stored,
            settings.telemetry_batch_size,
            settings.telemetry_flush_interval_s,
        )
        log.info("hub store: %s", engine.url.render_as_string(hide_password=True))
        cache = PrincipalCache(settings.principal_cache_s, settings.principal_cache_outage_s)
        accounts = Accounts(engine, cache, settings.password_hash_cost)
        await asyncio.to_thread(settings.spool_file.parent.mkdir, 0o700, True, True)
        spool = RowSpool(settings.spool_file, engine, [AuditRow, CommandRow])
        audit = AuditLog(engine, spool)
        await asyncio.to_thread(_bootstrap_accounts, accounts, audit, settings)
        hub = cls(
            settings=settings,
            engine=engine,
            repository=repository,
            registry=registry,
            bus=bus,
            dispatcher=CommandDispatcher(registry, settings.command_timeout_s),
            writer=writer,
            logbook=logbook,
            accounts=accounts,
            audit=audit,
            spool=spool,
            tiles=TileLibrary(settings.tiles_folder),
            param_catalog=ParamCatalog(settings.param_metadata_dir),
            denials=DenialCoalescer(settings.audit_denial_interval_s),
            login_limiter=RateLimiter(Limit(settings.login_attempts_per_minute, 60.0)),
            login_address_limiter=RateLimiter(
                Limit(settings.login_attempts_per_address_per_minute, 60.0)
            ),
            command_limiter=RateLimiter(Limit(settings.commands_per_second, 1.0)),
            passwords=PasswordWork(
                settings.password_hash_threads, settings.password_hash_max_pending
            ),
            safety=SafetyService(RailsRepository(engine), settings),
            scans=ScanService(
                ScanRepository(engine),
                bus,
                site=settings.site_frame(),
                voxel_m=settings.scan_voxel_m,
                max_voxels=settings.scan_map_max_voxels,
                max_rate_hz=settings.scan_max_rate_hz,
                queue_limit=settings.scan_queue_limit,
            ),
            fleet_link=fleet_link,
        )
        hub.manual_control = ManualControl(registry, hub.dispatcher, hub.client_feeds, hub.record)
        if fleet_link is not None:
            claims = LeaseClaims(LeaseClaimStore(engine), fleet_link.hub_id, fleet_link.lease_ttl_s)
            hub.manual_control.leases.claims = claims
            fleet_link.on_manual_ended = hub.manual_ended_elsewhere
            fleet_link.routes.check_sender = hub.routed_sender
            fleet_link.routes.carry_out = hub.carry_out_routed
        writer.on_sequences = hub.deliver_sequence_news
        hub.fanout = VehicleFanout(
            bus, settings.ui_vehicle_interval_s, settings.ui_batch_interval_s
        )
        hub.surveys = SurveyService(hub, bus, SurveyRepository(engine), settings)
        if fleet_link is not None:
            hub.surveys.ownership = SurveyOwnership(LeaseClaimStore(engine), fleet_link.hub_id)
        await hub.surveys.load()
        hub.mosaic = MosaicService(settings.data_dir / "mosaics", hub.survey_area)
        await hub.mosaic.load()
        hub.photos = PhotoIngest(
            PhotoRepository(engine),
            settings.photos_folder,
            hub.surveys.known,
            hub.surveys.find,
            margin_m=settings.photo_survey_margin_m,
            quota_bytes=settings.max_photo_bytes_per_vehicle,
            partials=PartialLimits(
                settings.photo_uploads_per_vehicle, settings.photo_upload_expiry_s
            ),
            sink=MosaicSink(hub.mosaic),
        )
        await hub.manual_control.revoke_left_open(engine)
        if settings.viz_enabled:
            hub.viz = await asyncio.to_thread(VizServer.start)
            hub.viz_http = httpx.AsyncClient(timeout=httpx.Timeout(10.0))
            frame = SceneFrame(parse_origin(settings.viz_origin))
            hub.scene = await asyncio.to_thread(
                FleetScene, hub.viz.viser, frame, settings.viz_trail_s
            )
            hub.replays = ReplayPanels(hub.viz.viser, frame, logbook)
            hub.viewers = Viewers(hub.viz.viser, hub.scene)
        return hub

    async def run(self) -> None:
        """The hub's long-running work; cancel it to stop (the writer flushes first)."""
        try:
            async with asyncio.TaskGroup() as tasks:
                tasks.create_task(self.writer.run())
                tasks.create_task(self.fanout.run())
                tasks.create_task(self.scans.run())
                tasks.create_task(self._watch_obstacles())
                tasks.create_task(self._publish_point_map())
                tasks.create_task(self._apply_retention())
                tasks.create_task(self._drain_spool())
                tasks.create_task(self._flush_denials())
                tasks.create_task(self.surveys.run())
                tasks.create_task(self.mosaic.run())
                tasks.create_task(self.photos.run())
                tasks.create_task(self.manual_control.watch_expiry())
                for work in self.background:
                    tasks.create_task(work())
                if self.fleet_link is not None:
                    tasks.create_task(self.fleet_link.run())
                if self.scene is not None:
                    mirror = SceneMirror(
                        self.scene,
                        self.bus,
                        self.registry,
                        self.settings.viz_update_interval_s,
                        surveys=self.surveys,
                        mosaics=self.mosaic,
                        mosaic_surveys=lambda: [run.id for run in self.surveys.known()],
                        layers=self.scene_layers,
                    )
                    tasks.create_task(mirror.run())
        finally:
            # The counts of refusals not yet written, before the store closes.
            await self._record_all(self.denials.closed(everything=True))
            if self.fleet_link is not None:
                await self.fleet_link.close()
            await asyncio.to_thread(self.mosaic.close)  # the tiles in memory to disk
            if self.viz_http is not None:
                await self.viz_http.aclose()
            if self.viz is not None:
                await asyncio.to_thread(self.viz.stop)
            self.passwords.close()
            self.tiles.close()
            self.engine.dispose()

    async def survey_area(self, survey_id: str) -> dict[str, Any] | None:
        """A survey's area as GeoJSON, for its mosaic's coverage (None: no such survey)."""
        try:
            run = await self.surveys.find(survey_id)
        except NotFound:
            return None
        area: dict[str, Any] = run.request.area.model_dump()
        return area

    async def manual_ended_elsewhere(self, vehicle_id: str, why: str) -> None:
        """Browser control ended on a vehicle whose agent another hub holds."""
        await self.manual_control.end_on_vehicle(vehicle_id, why)

    async def routed_sender(self, sender: RoutedSender) -> Principal | None:
        """The user a command routed from another hub names, per the shared database."""
        try:
            return await asyncio.to_thread(
                self.accounts.principal_of_token,
                sender.token_id,
                sender.name,
                sender.role,
                sender.token_kind,
            )
        except SQLAlchemyError as error:
            # Unverifiable is unknown: refused (the agent's own failsafes stand meanwhile).
            log.warning("routed command's sender %s not checked: %s", sender.name, error)
            return None

    async def carry_out_routed(
        self, principal: Principal, vehicle_id: str, routed: RoutedCommand
    ) -> CommandOutcome:
        return await carry_out_routed(self, principal, vehicle_id, routed)

    @property
    def routes(self) -> AgentRoutes | None:
        return None if self.fleet_link is None else self.fleet_link.routes

    def deliver_sequence_news(self, acks: dict[StreamKey, int], gaps: list[Gap]) -> None:
        """Tell each agent what is now stored and which of its frames never arrived."""
        for key, seq in acks.items():
            if (session := self.agent_sessions.get(key.vehicle_id)) is not None:
                session.acknowledge(key, seq)
        for gap in gaps:
            if (session := self.agent_sessions.get(gap.key.vehicle_id)) is not None:
                session.request_resend(gap)

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

    async def _apply_retention(self) -> None:
        policy = self.settings.retention_policy()
        if policy == RetentionPolicy():
            return
        while True:
            try:
                removed = await asyncio.to_thread(self.logbook.apply_retention, policy, time.time())
            except SQLAlchemyError as error:
                # Retention can wait for the next round; it must never stop the hub.
                log.warning("retention skipped: %s", error)
            else:
                if any(removed.values()):
                    log.info("retention removed %s", removed)
            await asyncio.sleep(self.settings.retention_interval_s)

    async def _watch_obstacles(self) -> None:
        """Obstacles found in the point map, or gone from it, as events."""
        while True:
            await asyncio.sleep(self.settings.scan_obstacle_interval_s)
            try:
                await self.refresh_obstacles()
            except Exception:
                # A map that cannot be clustered this time must never stop the hub.
                log.exception("obstacle extraction failed")

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

    async def _publish_point_map(self) -> None:
        """The point map to the feeds that subscribed to it, when it has changed, at most
        every POINT_MAP_PUBLISH_S: it changes little from one second to the next, and its
        newest voxels are the heaviest message on the feed."""
        published = -1
        while True:
            await asyncio.sleep(POINT_MAP_PUBLISH_S)
            version = self.scans.map_version
            if version == published or not self.bus.subscribers(Topic.MAP):
                continue
            published = version
            points: tuple[MapLayer] = ("points",)
            [update] = await self.map_now(points)
            await self.bus.publish(Topic.MAP, update.type, update)

    async def _drain_spool(self) -> None:
        """Store the rows spooled during a database outage as soon as it is over."""
        while True:
            if self.spool.pending:
                try:
                    await asyncio.to_thread(self.spool.drain)
                except OSError as error:
                    log.error("spooled rows could not be read or rewritten: %s", error)
            # Polling: an outage's end announces nothing.
            await asyncio.sleep(self.settings.spool_retry_s)

    async def store_event(
        self, vehicle_id: str, kind: HubEventKind, text: str, severity: int | None = None
    ) -> None:
        """An event the hub itself observed (a link coming up or going down, a refused
        second agent); ``severity`` is a MAV_SEVERITY."""
        event = StoredEvent(vehicle_id, "hub", None, time.time(), kind, severity, text)
        await self.bus.publish(Topic.STORAGE, vehicle_id, event)
        await self.publish_event(event)

    async def publish_event(self, event: StoredEvent) -> None:
        """To the dashboards' live feeds (whether or not it is stored)."""
        await self.bus.publish(Topic.VEHICLE_EVENT, event.vehicle_id, live_event(event))

    async def record(self, entry: AuditEntry) -> None:
        await asyncio.to_thread(self.audit.record, entry)

    async def record_denial(self, entry: AuditEntry, route: str, reason: str) -> None:
        """A refused request, coalesced with the same principal's same refusals
        (backend/audit_denials.py): a flood leaves a bounded trace."""
        await self._record_all(self.denials.admit(entry, route, reason))

    async def _record_all(self, entries: list[AuditEntry]) -> None:
        for entry in entries:
            await self.record(entry)

    async def _flush_denials(self) -> None:
        """Write the counts of refusal windows that have closed."""
        while True:
            await asyncio.sleep(self.denials.interval_s)
            await self._record_all(self.denials.closed())

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


def _bootstrap_accounts(accounts: Accounts, audit: AuditLog, settings: HubSettings) -> None:
    admin_password = settings.admin_password.get_secret_value() if settings.admin_password else None
    if admin_password is not None and settings.environment == "production":
        # The settings refuse the defaults that ship in examples; how guessable the rest
        # is, the account policy says, as it does for every account's password.
        weakness = password_problem(admin_password, settings.admin_username)
        if weakness:
            raise ValueError(f"refusing a weak secret in production: GCS_ADMIN_PASSWORD {weakness}")
    generated = accounts.ensure_first_admin(settings.admin_username, admin_password)
    if generated is not None:
        # Shown once, on the console and never in the log, as the issue of a secret.
        print(
            f"\nCreated the first admin account: user {settings.admin_username!r}, "
            f"password {generated}\n"
            "It is not shown again. Set GCS_ADMIN_PASSWORD to choose it instead.\n",
            flush=True,
        )
    configured = settings.enrolment_tokens()
    for vehicle_id, token in configured.items():
        if accounts.provision_agent_token(vehicle_id, token):
            log.info("enrolled vehicle %s from GCS_AGENT_TOKENS", vehicle_id)
    # A token rotated or removed in the configuration must stop working, not linger.
    for row in accounts.revoke_unprovisioned(configured):
        log.warning(
            "revoked agent token %d of %s: no longer in GCS_AGENT_TOKENS", row.id, row.vehicle_id
        )
        audit.record(
            AuditEntry(
                actor=PROVISIONING,
                role="system",
                source="GCS_AGENT_TOKENS",
                action=AuditAction.AGENT_TOKEN_REVOKE,
                target=row.vehicle_id,
                outcome="ok",
                detail={"id": row.id, "reason": "no longer in GCS_AGENT_TOKENS"},
            )
        )
