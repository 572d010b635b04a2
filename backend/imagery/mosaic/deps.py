"""The mosaic routes' typed FastAPI dependency: the mosaics, never the hub (the offline
tile library, where a mosaic is installed as a base map, is the API's ``TilesDep``,
``backend/api/deps.py``).

The app provides it on its state when the hub starts (``app.py``); a route declares
``mosaics: MosaicsDep`` and is handed it.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Annotated

from fastapi import Depends
from starlette.datastructures import State
from starlette.requests import HTTPConnection

from backend.imagery.mosaic.service import MosaicService

STATE_KEY = "mosaics"


@dataclass(frozen=True)
class MosaicRoutesUse:
    """What the mosaic routes use of the running hub."""

    mosaics: MosaicService


def provide(state: State, mosaics: MosaicService) -> None:
    """Make this the one the routes are handed (the app's lifespan calls this)."""
    setattr(state, STATE_KEY, MosaicRoutesUse(mosaics))


def _provided(connection: HTTPConnection) -> MosaicRoutesUse:
    provided: MosaicRoutesUse = getattr(connection.app.state, STATE_KEY)
    return provided


def get_mosaics(connection: HTTPConnection) -> MosaicService:
    return _provided(connection).mosaics


MosaicsDep = Annotated[MosaicService, Depends(get_mosaics)]
