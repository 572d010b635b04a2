"""The formation routes' typed dependencies: the formation service app.py wired, and the
audit log they record in."""

from __future__ import annotations

from typing import Annotated

from fastapi import Depends
from starlette.requests import HTTPConnection

from backend.api.deps import HubDep
from backend.audit import AuditLog
from backend.formation.service import FormationService


def formation_service(connection: HTTPConnection) -> FormationService:
    service: FormationService = connection.app.state.formation
    return service


def audit_log(hub: HubDep) -> AuditLog:
    return hub.audit


FormationServiceDep = Annotated[FormationService, Depends(formation_service)]
AuditLogDep = Annotated[AuditLog, Depends(audit_log)]
