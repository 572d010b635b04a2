"""What the command path needs of the hub, as a structural type.

The hub (``backend.hub.services.Hub``) wires these collaborators once per process and sits above
this layer, so the fleet's services never import it: they declare here what they use, and
the API layer hands them the hub, which provides all of it.
"""

from __future__ import annotations

from typing import Protocol

from backend.audit import AuditEntry
from backend.fleet.commands import CommandDispatcher
from backend.fleet.param_catalog import ParamCatalog
from backend.fleet.registry import FleetRegistry
from backend.safety.service import SafetyService
from backend.storage.spool import RowSpool
from protocol.messages import HubEventKind


class CommandServices(Protocol):
    """What sending one command uses (``backend.fleet.command_service``)."""

    @property
    def dispatcher(self) -> CommandDispatcher: ...

    @property
    def safety(self) -> SafetyService: ...

    @property
    def registry(self) -> FleetRegistry: ...

    @property
    def spool(self) -> RowSpool: ...

    @property
    def param_catalog(self) -> ParamCatalog: ...

    async def record(self, entry: AuditEntry) -> None: ...

    async def store_event(
        self, vehicle_id: str, kind: HubEventKind, text: str, severity: int | None = None
    ) -> None: ...
