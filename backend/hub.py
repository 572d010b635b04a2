"""The hub's services, wired once per process; the API layer reaches them through this."""

from __future__ import annotations

import asyncio
import logging
from dataclasses import dataclass

from sqlalchemy import Engine

from backend.fleet.commands import CommandDispatcher
from backend.fleet.registry import FleetRegistry, VehicleRecord
from backend.realtime.bus import InProcessBus, ReliableSubscription, Topic
from backend.settings import HubSettings
from backend.storage.database import make_engine, migrate
from backend.storage.repository import Repository
from backend.storage.writer import TelemetryWriter

log = logging.getLogger(__name__)


@dataclass
class Hub:
    settings: HubSettings
    engine: Engine
    repository: Repository
    registry: FleetRegistry
    bus: InProcessBus
    dispatcher: CommandDispatcher
    writer: TelemetryWriter

    @classmethod
    async def start(cls, settings: HubSettings) -> Hub:
        """Open the store (migrating it) and load the vehicles it knows."""
        engine = make_engine(settings.sqlalchemy_url)
        await asyncio.to_thread(migrate, engine)
        repository = Repository(engine)
        registry = FleetRegistry()
        registry.load(await asyncio.to_thread(repository.vehicles))
        bus = InProcessBus()
        stored = ReliableSubscription(settings.telemetry_queue_limit)
        bus.subscribe(Topic.TELEMETRY, stored)
        writer = TelemetryWriter(
            repository, stored, settings.telemetry_batch_size, settings.telemetry_flush_interval_s
        )
        log.info("hub store: %s", engine.url.render_as_string(hide_password=True))
        return cls(
            settings=settings,
            engine=engine,
            repository=repository,
            registry=registry,
            bus=bus,
            dispatcher=CommandDispatcher(registry, settings.command_timeout_s),
            writer=writer,
        )

    async def run(self) -> None:
        """The hub's long-running work; cancel it to stop (the writer flushes first)."""
        try:
            async with asyncio.TaskGroup() as tasks:
                tasks.create_task(self.writer.run())
        finally:
            self.engine.dispose()

    async def publish_state(self, record: VehicleRecord) -> None:
        await self.bus.publish(Topic.VEHICLE_STATE, record.id, record.summary())
