"""The photo routes' typed FastAPI dependencies: the photo ingest and the fleet's vehicles,
never the hub.

The app provides them on its state when the hub starts (``app.py``); a route declares
``photos: PhotosDep`` or ``vehicles: VehiclesDep`` and is handed it.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Annotated, Protocol

from fastapi import Depends
from starlette.datastructures import State
from starlette.requests import HTTPConnection

from backend.imagery.photos.ingest import PhotoIngest

STATE_KEY = "photos"


class VehicleDirectory(Protocol):
    """The fleet's registry: a vehicle by id, or NotFound (404)."""

    def get(self, vehicle_id: str) -> object: ...


@dataclass(frozen=True)
class PhotoRoutesUse:
    """What the photo routes use of the running hub."""

    photos: PhotoIngest
    vehicles: VehicleDirectory


def provide(state: State, photos: PhotoIngest, vehicles: VehicleDirectory) -> None:
    """Make these the ones the routes are handed (the app's lifespan calls this)."""
    setattr(state, STATE_KEY, PhotoRoutesUse(photos, vehicles))


def _provided(connection: HTTPConnection) -> PhotoRoutesUse:
    provided: PhotoRoutesUse = getattr(connection.app.state, STATE_KEY)
    return provided


def get_photos(connection: HTTPConnection) -> PhotoIngest:
    return _provided(connection).photos


def get_vehicles(connection: HTTPConnection) -> VehicleDirectory:
    return _provided(connection).vehicles


PhotosDep = Annotated[PhotoIngest, Depends(get_photos)]
VehiclesDep = Annotated[VehicleDirectory, Depends(get_vehicles)]
