"""Typed FastAPI dependencies of the safety routes: the safety service, the fleet's
vehicles and the audit log, each as what the routes use of it, so that the routes never
reach the hub object (which sits above this package and is never imported here)."""

from __future__ import annotations

from typing import Annotated, Protocol

from fastapi import Depends
from starlette.requests import HTTPConnection

from backend.audit import AuditEntry
from backend.safety.service import SafetyService
from backend.safety.snapshot import ReportedVehicle


class VehicleDirectory(Protocol):
    """The fleet's registry: a vehicle by id, or NotFound (404)."""

    def get(self, vehicle_id: str) -> ReportedVehicle: ...


class AuditLog(Protocol):
    async def record(self, entry: AuditEntry) -> None: ...


class _SafetyHost(AuditLog, Protocol):
    """What the routes use of the process's wiring (``backend.hub.services.Hub`` provides it)."""

    @property
    def safety(self) -> SafetyService: ...

    @property
    def registry(self) -> VehicleDirectory: ...


def _host(connection: HTTPConnection) -> _SafetyHost:
    host: _SafetyHost = connection.app.state.hub
    return host


def get_safety(connection: HTTPConnection) -> SafetyService:
    return _host(connection).safety


def get_vehicles(connection: HTTPConnection) -> VehicleDirectory:
    return _host(connection).registry


def get_audit_log(connection: HTTPConnection) -> AuditLog:
    return _host(connection)


SafetyDep = Annotated[SafetyService, Depends(get_safety)]
VehiclesDep = Annotated[VehicleDirectory, Depends(get_vehicles)]
AuditLogDep = Annotated[AuditLog, Depends(get_audit_log)]
