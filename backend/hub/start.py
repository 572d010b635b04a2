"""Building the hub: the store (migrated), the bus, the accounts and every service, and
the features' collaborators joined."""

from __future__ import annotations

import asyncio
import logging
from dataclasses import dataclass

import httpx

from backend.audit import AuditAction, AuditEntry, AuditLog
from backend.audit_denials import DenialCoalescer
from backend.auth.accounts import PROVISIONING, Accounts
from backend.auth.password_policy import password_problem
from backend.auth.password_work import PasswordWork
from backend.auth.principal_cache import PrincipalCache
from backend.auth.rate_limit import Limit, RateLimiter
from backend.fleet.commands import CommandDispatcher
from backend.fleet.param_catalog import ParamCatalog
from backend.fleet.registry import FleetRegistry
from backend.hub.collaborators import CommandPath, RoutedSenders, SequenceNews, SurveyAreas
from backend.hub.multi_hub import link_hubs
from backend.hub.services import Hub
from backend.imagery.mosaic.service import MosaicService
from backend.imagery.photos.ingest import PhotoIngest
from backend.imagery.photos.partials import PartialLimits
from backend.imagery.photos.repository import PhotoRepository
from backend.imagery.sink import MosaicSink
from backend.manual_control.service import ManualControl
from backend.mapping.tiles import TileLibrary
from backend.realtime.bus import InProcessBus, ReliableSubscription, Topic
from backend.realtime.collaborators import AgentConnection, ClientConnection
from backend.realtime.fleet_link import FleetLink
from backend.realtime.live_events import RecentEvents
from backend.realtime.nats_bus import NatsBus
from backend.realtime.vehicle_fanout import VehicleFanout
from backend.safety.rails_store import RailsRepository
from backend.safety.service import SafetyService
from backend.scans.repository import ScanRepository
from backend.scans.service import ScanService
from backend.settings import HubSettings
from backend.storage.database import make_engine, migrate
from backend.storage.logbook import Logbook
from backend.storage.models import AuditRow, CommandRow
from backend.storage.repository import Repository
from backend.storage.spool import RowSpool
from backend.storage.writer import StorageWriter
from backend.survey.repository import SurveyRepository
from backend.survey.service import SurveyService
from backend.viz3d.frame import SceneFrame, parse_origin
from backend.viz3d.replay import ReplayPanels
from backend.viz3d.scene import FleetScene
from backend.viz3d.server import VizServer
from backend.viz3d.viewers import Viewers

log = logging.getLogger(__name__)


async def start_hub(settings: HubSettings) -> Hub:
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
    dispatcher = CommandDispatcher(registry, settings.command_timeout_s)
    safety = SafetyService(RailsRepository(engine), settings)
    param_catalog = ParamCatalog(settings.param_metadata_dir)
    commands = CommandPath(dispatcher, safety, registry, spool, param_catalog, audit, bus)
    scans = ScanService(
        ScanRepository(engine),
        bus,
        site=settings.site_frame(),
        voxel_m=settings.scan_voxel_m,
        max_voxels=settings.scan_map_max_voxels,
        max_rate_hz=settings.scan_max_rate_hz,
        queue_limit=settings.scan_queue_limit,
    )
    # Live agent connections and client feeds, as they come and go: the services that
    # reach them hold the collections themselves.
    agent_sessions: dict[str, AgentConnection] = {}
    client_feeds: set[ClientConnection] = set()
    writer.on_sequences = SequenceNews(agent_sessions)
    manual_control = ManualControl(registry, dispatcher, client_feeds, commands.record)
    fanout = VehicleFanout(bus, settings.ui_vehicle_interval_s, settings.ui_batch_interval_s)
    surveys = SurveyService(commands, bus, SurveyRepository(engine), settings)
    if fleet_link is not None:
        senders = RoutedSenders(accounts)
        link_hubs(fleet_link, engine, commands, senders, manual_control, surveys)
    await surveys.load()
    mosaic = MosaicService(settings.data_dir / "mosaics", SurveyAreas(surveys))
    await mosaic.load()
    photos = PhotoIngest(
        PhotoRepository(engine),
        settings.photos_folder,
        surveys.known,
        surveys.find,
        margin_m=settings.photo_survey_margin_m,
        quota_bytes=settings.max_photo_bytes_per_vehicle,
        partials=PartialLimits(settings.photo_uploads_per_vehicle, settings.photo_upload_expiry_s),
        sink=MosaicSink(mosaic),
    )
    await manual_control.revoke_left_open(engine)
    view = await View3D.start(settings, logbook) if settings.viz_enabled else View3D()
    recent_events = RecentEvents()
    bus.subscribe(Topic.VEHICLE_EVENT, recent_events)
    return Hub(
        recent_events=recent_events,
        settings=settings,
        engine=engine,
        repository=repository,
        registry=registry,
        bus=bus,
        commands=commands,
        dispatcher=dispatcher,
        writer=writer,
        logbook=logbook,
        accounts=accounts,
        audit=audit,
        spool=spool,
        tiles=TileLibrary(settings.tiles_folder),
        param_catalog=param_catalog,
        denials=DenialCoalescer(settings.audit_denial_interval_s),
        login_limiter=RateLimiter(Limit(settings.login_attempts_per_minute, 60.0)),
        login_address_limiter=RateLimiter(
            Limit(settings.login_attempts_per_address_per_minute, 60.0)
        ),
        command_limiter=RateLimiter(Limit(settings.commands_per_second, 1.0)),
        passwords=PasswordWork(settings.password_hash_threads, settings.password_hash_max_pending),
        safety=safety,
        scans=scans,
        agent_sessions=agent_sessions,
        client_feeds=client_feeds,
        manual_control=manual_control,
        fanout=fanout,
        fleet_link=fleet_link,
        surveys=surveys,
        mosaic=mosaic,
        photos=photos,
        viz=view.server,
        viz_http=view.http,
        scene=view.scene,
        replays=view.replays,
        viewers=view.viewers,
    )


@dataclass(frozen=True)
class View3D:
    """The 3D view: viser on loopback, the client that passes its page on, the fleet's
    scene, the replay panels and the viewers (all None when GCS_VIZ_ENABLED is false)."""

    server: VizServer | None = None
    http: httpx.AsyncClient | None = None
    scene: FleetScene | None = None
    replays: ReplayPanels | None = None
    viewers: Viewers | None = None

    @classmethod
    async def start(cls, settings: HubSettings, logbook: Logbook) -> View3D:
        server = await asyncio.to_thread(VizServer.start)
        frame = SceneFrame(parse_origin(settings.viz_origin))
        scene = await asyncio.to_thread(FleetScene, server.viser, frame, settings.viz_trail_s)
        return cls(
            server=server,
            http=httpx.AsyncClient(timeout=httpx.Timeout(10.0)),
            scene=scene,
            replays=ReplayPanels(server.viser, frame, logbook),
            viewers=Viewers(server.viser, scene),
        )


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
