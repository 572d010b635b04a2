"""The collaborators the hub's services are built with, made before the ``Hub`` that holds
them, so that no service is handed the hub itself (``start.py`` builds them in order)."""

from __future__ import annotations

import asyncio
import logging
import time
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from sqlalchemy.exc import SQLAlchemyError

from backend.audit import AuditEntry, AuditLog
from backend.auth.accounts import Accounts
from backend.auth.policy import Principal
from backend.errors import NotFound
from backend.fleet.commands import CommandDispatcher
from backend.fleet.param_catalog import ParamCatalog
from backend.fleet.registry import FleetRegistry
from backend.realtime.bus import Bus, Topic
from backend.realtime.collaborators import AgentConnection
from backend.realtime.live_events import live_event
from backend.safety.service import SafetyService
from backend.storage.records import StoredEvent
from backend.storage.sequences import Gap, StreamKey
from backend.storage.spool import RowSpool
from backend.survey.service import SurveyService
from protocol.messages import HubEventKind
from protocol.routing import RoutedSender

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class CommandPath:
    """What sending a command uses (``backend.fleet.collaborators.CommandServices``): the
    routes, the surveys and the commands routed from another hub all send through it."""

    dispatcher: CommandDispatcher
    safety: SafetyService
    registry: FleetRegistry
    spool: RowSpool
    param_catalog: ParamCatalog
    audit: AuditLog
    bus: Bus

    async def record(self, entry: AuditEntry) -> None:
        await asyncio.to_thread(self.audit.record, entry)

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


class SequenceNews:
    """The writer's news to the agents: what is now stored, and which of their frames
    never arrived (``StorageWriter.on_sequences``)."""

    def __init__(self, sessions: Mapping[str, AgentConnection]) -> None:
        self._sessions = sessions  # the hub's live agent connections, as they come and go

    def __call__(self, acks: dict[StreamKey, int], gaps: list[Gap]) -> None:
        for key, seq in acks.items():
            if (session := self._sessions.get(key.vehicle_id)) is not None:
                session.acknowledge(key, seq)
        for gap in gaps:
            if (session := self._sessions.get(gap.key.vehicle_id)) is not None:
                session.request_resend(gap)


class SurveyAreas:
    """A survey's area as GeoJSON, for its mosaic's coverage (None: no such survey)."""

    def __init__(self, surveys: SurveyService) -> None:
        self._surveys = surveys

    async def __call__(self, survey_id: str) -> dict[str, Any] | None:
        try:
            run = await self._surveys.find(survey_id)
        except NotFound:
            return None
        area: dict[str, Any] = run.request.area.model_dump()
        return area


class RoutedSenders:
    """The user a command routed from another hub names, per the shared database."""

    def __init__(self, accounts: Accounts) -> None:
        self._accounts = accounts

    async def __call__(self, sender: RoutedSender) -> Principal | None:
        try:
            return await asyncio.to_thread(
                self._accounts.principal_of_token,
                sender.token_id,
                sender.name,
                sender.role,
                sender.token_kind,
            )
        except SQLAlchemyError as error:
            # Unverifiable is unknown: refused (the agent's own failsafes stand meanwhile).
            log.warning("routed command's sender %s not checked: %s", sender.name, error)
            return None
