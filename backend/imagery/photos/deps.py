"""The photo routes' typed FastAPI dependency: the photo ingest, never the hub (the fleet's
registry they also read is the API's ``RegistryDep``, ``backend/api/deps.py``).

The app provides it on its state when the hub starts (``app.py``); a route declares
``photos: PhotosDep`` and is handed it.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Annotated

from fastapi import Depends
from starlette.datastructures import State
from starlette.requests import HTTPConnection

from backend.imagery.photos.ingest import PhotoIngest

STATE_KEY = "photos"


@dataclass(frozen=True)
class PhotoRoutesUse:
    """What the photo routes use of the running hub."""

    photos: PhotoIngest


def provide(state: State, photos: PhotoIngest) -> None:
    """Make this the one the routes are handed (the app's lifespan calls this)."""
    setattr(state, STATE_KEY, PhotoRoutesUse(photos))


def _provided(connection: HTTPConnection) -> PhotoRoutesUse:
    provided: PhotoRoutesUse = getattr(connection.app.state, STATE_KEY)
    return provided


def get_photos(connection: HTTPConnection) -> PhotoIngest:
    return _provided(connection).photos


PhotosDep = Annotated[PhotoIngest, Depends(get_photos)]
