"""The mosaic routes' typed FastAPI dependencies: the mosaics and the offline tile library
(where a mosaic is installed as a base map), never the hub.

The app provides them on its state when the hub starts (``app.py``); a route declares
``mosaics: MosaicsDep`` or ``tiles: TileLibraryDep`` and is handed it.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Annotated

from fastapi import Depends
from starlette.datastructures import State
from starlette.requests import HTTPConnection

from backend.imagery.mosaic.service import MosaicService
from backend.mapping.tiles import TileLibrary

STATE_KEY = "mosaics"


@dataclass(frozen=True)
class MosaicRoutesUse:
    """What the mosaic routes use of the running hub."""

    mosaics: MosaicService
    tiles: TileLibrary


def provide(state: State, mosaics: MosaicService, tiles: TileLibrary) -> None:
    """Make these the ones the routes are handed (the app's lifespan calls this)."""
    setattr(state, STATE_KEY, MosaicRoutesUse(mosaics, tiles))


def _provided(connection: HTTPConnection) -> MosaicRoutesUse:
    provided: MosaicRoutesUse = getattr(connection.app.state, STATE_KEY)
    return provided


def get_mosaics(connection: HTTPConnection) -> MosaicService:
    return _provided(connection).mosaics


def get_tile_library(connection: HTTPConnection) -> TileLibrary:
    return _provided(connection).tiles


MosaicsDep = Annotated[MosaicService, Depends(get_mosaics)]
TileLibraryDep = Annotated[TileLibrary, Depends(get_tile_library)]
