"""One hub's link to the others (several hubs, docs/deployer.md "Several hubs"): one NATS
connection that carries the shared bus (backend/realtime/nats_bus.py) and the routes to
agents connected elsewhere (backend/realtime/routing.py), and mirrors the other hubs'
vehicles into this hub's registry so that its dashboards, commands and leases reach them.
"""

from __future__ import annotations

import asyncio
import logging
import os
import socket
import ssl
import time
import uuid
from collections.abc import Awaitable, Callable
from typing import Any

import nats
from nats.aio.client import Client as Nats

from backend.fleet.registry import FleetRegistry
from backend.manual_control.service import ends_manual_control
from backend.realtime.bus import Topic
from backend.realtime.nats_bus import NatsBus
from backend.realtime.routing import AgentRoutes, RemoteChannel
from backend.settings import HubSettings, redacted_url
from protocol.messages import LiveEvent, VehicleSummary

log = logging.getLogger(__name__)

# A lease claim outlives its last renewal by this much beyond the lease's own expiry, so
# a renewal late by a busy database does not hand the vehicle to someone else.
LEASE_CLAIM_MARGIN_S = 2.0
LEASE_EXPIRY_S = 2.0  # backend.manual_control.lease.LeaseLimits' default
# A vehicle of another hub not heard of for this long is asked after; if no hub answers
# for it (its hub died, and its agent has not reconnected elsewhere yet), it is shown
# offline here rather than connected for ever.
REMOTE_SILENCE_S = 3.0
PRESENCE_TIMEOUT_S = 1.0


def bus_credentials(settings: HubSettings) -> dict[str, Any]:
    """nats-py's options for the credentials and TLS the settings give (a user and
    password in the URL nats-py takes from the URL itself)."""
    options: dict[str, Any] = {}
    if settings.bus_user is not None and settings.bus_password is not None:
        options["user"] = settings.bus_user
        options["password"] = settings.bus_password.get_secret_value()
    if settings.bus_creds_file is not None:
        options["user_credentials"] = str(settings.bus_creds_file)
    if settings.bus_tls_ca_file is not None:
        options["tls"] = ssl.create_default_context(cafile=str(settings.bus_tls_ca_file))
    return options


class FleetLink:
    def __init__(self, connection: Nats, prefix: str, registry: FleetRegistry, margin_s: float):
        self.nats = connection
        # At most 64 characters, the width of a claim's holder column.
        self.hub_id = f"{socket.gethostname()[:48]}-{os.getpid()}-{uuid.uuid4().hex[:6]}"
        self.bus = NatsBus(connection, prefix)
        self.routes = AgentRoutes(connection, prefix, registry, margin_s)
        self.routes.hub_id = self.hub_id
        self.lease_ttl_s = LEASE_EXPIRY_S + LEASE_CLAIM_MARGIN_S
        self._registry = registry
        self.bus.on_remote = self._mirror
        # Browser control ended on a vehicle connected to another hub (its deadman, the
        # RC pilot's mode change): a lease granted here must end with it.
        self.on_manual_ended: Callable[[str, str], Awaitable[None]] | None = None
        self._heard_at: dict[str, float] = {}  # remote vehicles, monotonic

    @classmethod
    async def connect(cls, settings: HubSettings, registry: FleetRegistry) -> FleetLink:
        assert settings.bus_url is not None

        async def disconnected() -> None:
            log.warning("NATS link lost: other hubs' vehicles are out of reach meanwhile")

        async def reconnected() -> None:
            log.info("NATS link back")

        async def error(problem: Exception) -> None:
            log.warning("NATS: %r", problem)

        options: dict[str, Any] = {
            "servers": [settings.bus_url],
            "name": f"gcs-hub-{settings.port}",
            # A hub hears only the others: what it publishes it has delivered itself.
            "no_echo": True,
            "max_reconnect_attempts": -1,
            "disconnected_cb": disconnected,
            "reconnected_cb": reconnected,
            "error_cb": error,
        }
        options.update(bus_credentials(settings))
        connection = await nats.connect(**options)
        link = cls(connection, settings.bus_prefix, registry, settings.bus_request_timeout_s)
        log.info("joined the hubs on %s as %s", redacted_url(settings.bus_url), link.hub_id)
        return link

    async def run(self) -> None:
        async with asyncio.TaskGroup() as tasks:
            tasks.create_task(self.bus.run())
            tasks.create_task(self._watch_silent_vehicles())

    async def _watch_silent_vehicles(self) -> None:
        while True:
            await asyncio.sleep(REMOTE_SILENCE_S)  # polling: silence announces nothing
            now = time.monotonic()
            for vehicle_id, heard_at in list(self._heard_at.items()):
                if now - heard_at < REMOTE_SILENCE_S:
                    continue
                record = self._registry.get(vehicle_id)
                channel = record.channel
                if channel is None or not channel.remote:
                    self._heard_at.pop(vehicle_id, None)
                    continue
                if await self.routes.is_held(vehicle_id, PRESENCE_TIMEOUT_S):
                    self._heard_at[vehicle_id] = time.monotonic()
                    continue
                if record.channel is channel:  # unchanged while we asked
                    log.warning("%s: no hub holds its agent any more; shown offline", vehicle_id)
                    record.channel = None
                    self._heard_at.pop(vehicle_id, None)
                    await self.bus.publish_here(Topic.VEHICLE_STATE, vehicle_id, record.summary())

    async def close(self) -> None:
        await self.routes.close()
        try:
            await self.nats.drain()
        except Exception as error:
            # Closing with the hub: a link already gone has nothing to flush.
            log.info("NATS drain: %r", error)

    async def _mirror(self, topic: Topic, message: Any) -> None:
        if topic is Topic.VEHICLE_STATE and isinstance(message, VehicleSummary):
            routes = self.routes
            record = self._registry.mirror(message, lambda: RemoteChannel(routes, message.id))
            if record is not None and record.channel is not None:
                self._heard_at[message.id] = time.monotonic()
        elif (
            isinstance(message, LiveEvent)
            and ends_manual_control(message.kind, message.severity)
            and self.on_manual_ended is not None
        ):
            await self.on_manual_ended(message.vehicle_id, message.text)
