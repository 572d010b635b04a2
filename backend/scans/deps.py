"""The scan routes' typed FastAPI dependencies: the scan service and what the routes read
beside it, never the hub.

The app hands them over when the hub starts (``app.py`` calls ``provide``); a route
declares ``scans: ScansDep`` (or ``fleet: FleetDep``, ...) and is handed it.
"""

from __future__ import annotations

from collections.abc import Awaitable, Callable
from dataclasses import dataclass
from typing import Annotated

from fastapi import Depends
from starlette.datastructures import State
from starlette.requests import HTTPConnection

from backend.fleet.registry import FleetRegistry
from backend.scans.pointmap import MapObstacle
from backend.scans.service import ScanService
from backend.storage.logbook import Logbook

STATE_KEY = "scans"

# The point map's obstacles now, with lasting ids; the changes since the last look are
# told as events and on the live feed (the hub's ``refresh_obstacles`` does both).
RefreshObstacles = Callable[[], Awaitable[list[MapObstacle]]]


@dataclass(frozen=True)
class ScanRouteServices:
    scans: ScanService
    fleet: FleetRegistry  # a route about a vehicle first checks it is known (404)
    logbook: Logbook  # a flight's time range, for its points
    refresh_obstacles: RefreshObstacles


def provide(state: State, services: ScanRouteServices) -> None:
    """Make these the ones the routes are handed (the app's lifespan calls this)."""
    setattr(state, STATE_KEY, services)


def _services(connection: HTTPConnection) -> ScanRouteServices:
    services: ScanRouteServices = getattr(connection.app.state, STATE_KEY)
    return services


def get_scans(connection: HTTPConnection) -> ScanService:
    return _services(connection).scans


def get_fleet(connection: HTTPConnection) -> FleetRegistry:
    return _services(connection).fleet


def get_logbook(connection: HTTPConnection) -> Logbook:
    return _services(connection).logbook


def get_refresh_obstacles(connection: HTTPConnection) -> RefreshObstacles:
    return _services(connection).refresh_obstacles


ScansDep = Annotated[ScanService, Depends(get_scans)]
FleetDep = Annotated[FleetRegistry, Depends(get_fleet)]
LogbookDep = Annotated[Logbook, Depends(get_logbook)]
RefreshObstaclesDep = Annotated[RefreshObstacles, Depends(get_refresh_obstacles)]
