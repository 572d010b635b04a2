"""The formation routes' typed dependency: the formation service app.py wired (the audit
log they record in is the API's ``AuditLogDep``)."""

from __future__ import annotations

from typing import Annotated

from fastapi import Depends
from starlette.requests import HTTPConnection

from backend.formation.service import FormationService


def formation_service(connection: HTTPConnection) -> FormationService:
    service: FormationService = connection.app.state.formation
    return service


FormationServiceDep = Annotated[FormationService, Depends(formation_service)]
