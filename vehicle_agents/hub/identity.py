"""Which vehicle id the agent will use, asked before the first flight (`--print-id`)."""

from __future__ import annotations

import asyncio

from vehicle_agents.config import AgentSettings, default_vehicle_id
from vehicle_agents.fcu.link import FcuLink


async def identify(settings: AgentSettings, timeout_s: float) -> str:
    """The configured id, else ``<vehicle type>_<machine id>`` with the type the flight
    controller's first heartbeat names, as `run_agent` chooses it. TimeoutError if no
    heartbeat comes within ``timeout_s``."""
    if settings.vehicle_id is not None:
        return settings.vehicle_id
    link = FcuLink(settings.fcu, source_system=settings.source_system)
    reader = asyncio.create_task(link.run())
    try:
        async with asyncio.timeout(timeout_s):
            await link.wait_identified()
    finally:
        reader.cancel()
        await asyncio.gather(reader, return_exceptions=True)
    assert link.modes is not None
    return default_vehicle_id(link.modes.vehicle_type)
