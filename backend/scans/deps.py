"""The scan routes' typed FastAPI dependencies: the scan service and the obstacles'
refresh, never the hub. The fleet's registry and the logbook the routes also read are the
API's (``backend/api/deps.py``'s ``RegistryDep`` and ``LogbookDep``).

The app hands them over when the hub starts (``app.py`` calls ``provide``); a route
declares ``scans: ScansDep`` and is handed it.
"""

from __future__ import annotations

from collections.abc import Awaitable, Callable
from dataclasses import dataclass
from typing import Annotated

from fastapi import Depends
from starlette.datastructures import State
from starlette.requests import HTTPConnection

from backend.scans.pointmap import MapObstacle
from backend.scans.service import ScanService

STATE_KEY = "scans"

# The point map's obstacles now, with lasting ids; the changes since the last look are
# told as events and on the live feed (the hub's ``refresh_obstacles`` does both).
RefreshObstacles = Callable[[], Awaitable[list[MapObstacle]]]


@dataclass(frozen=True)
class ScanRouteServices:
    scans: ScanService
    refresh_obstacles: RefreshObstacles


def provide(state: State, services: ScanRouteServices) -> None:
    """Make these the ones the routes are handed (the app's lifespan calls this)."""
    setattr(state, STATE_KEY, services)


def _services(connection: HTTPConnection) -> ScanRouteServices:
    services: ScanRouteServices = getattr(connection.app.state, STATE_KEY)
    return services


def get_scans(connection: HTTPConnection) -> ScanService:
    return _services(connection).scans


def get_refresh_obstacles(connection: HTTPConnection) -> RefreshObstacles:
    return _services(connection).refresh_obstacles


ScansDep = Annotated[ScanService, Depends(get_scans)]
RefreshObstaclesDep = Annotated[RefreshObstacles, Depends(get_refresh_obstacles)]
