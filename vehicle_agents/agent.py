"""The agent process: one flight controller, one hub, telemetry and commands between."""

from __future__ import annotations

import asyncio
import logging
import time
import uuid

from gcs.protocol import PROTOCOL_VERSION, Hello, Telemetry, encode
from vehicle_agents import __version__
from vehicle_agents.commands import CommandExecutor
from vehicle_agents.config import AgentSettings, default_vehicle_id
from vehicle_agents.fcu_link import FcuLink
from vehicle_agents.hub_link import HubLink
from vehicle_agents.outbox import Outbox
from vehicle_agents.telemetry import snapshot

log = logging.getLogger(__name__)

CAPABILITIES = ["telemetry", "commands"]


async def run_agent(settings: AgentSettings) -> None:
    link = FcuLink(settings.fcu, source_system=settings.source_system)
    outbox = Outbox(settings.outbox_limit)
    async with asyncio.TaskGroup() as tasks:
        tasks.create_task(link.run())
        log.info("waiting for a heartbeat from %s", settings.fcu)
        await link.wait_identified()
        assert link.modes is not None
        assert link.target_system is not None
        vehicle_id = settings.vehicle_id or default_vehicle_id(link.modes.vehicle_type)
        hello = Hello(
            protocol=PROTOCOL_VERSION,
            vehicle_id=vehicle_id,
            autopilot=link.modes.autopilot,
            vehicle_type=link.modes.vehicle_type,
            system_id=link.target_system,
            modes=link.modes.names,
            capabilities=CAPABILITIES,
            agent_version=__version__,
            stream_id=uuid.uuid4().hex[:16],
        )
        executor = CommandExecutor(link)
        hub = HubLink(
            settings.hub, settings.token.get_secret_value(), hello, outbox, executor.execute
        )
        tasks.create_task(publish_telemetry(link, outbox, settings.telemetry_rate_hz))
        tasks.create_task(hub.run())


async def publish_telemetry(link: FcuLink, outbox: Outbox, rate_hz: float) -> None:
    """Snapshot the vehicle at a fixed rate into the outbox, numbering each one."""
    period = 1.0 / rate_hz
    seq = 0
    next_at = time.monotonic()
    while True:
        state = snapshot(link.latest, link.connected)
        outbox.put(encode(Telemetry(seq=seq, time=time.time(), state=state)))
        seq += 1
        next_at += period
        await asyncio.sleep(max(0.0, next_at - time.monotonic()))
