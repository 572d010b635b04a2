"""The whole hub as a route dependency, for the routes not yet on typed dependencies.

Only ``backend/api/photos.py``, ``mosaics.py`` and ``scans.py`` use it, while they move
into their feature folders; ``pyproject.toml``'s ``routes-without-hub`` contract names
them as its only exceptions. Every other route takes what it needs from
``backend/api/deps.py``.
"""

from __future__ import annotations

from typing import Annotated

from fastapi import Depends
from starlette.requests import HTTPConnection

from backend.hub.services import Hub


def get_hub(connection: HTTPConnection) -> Hub:
    hub: Hub = connection.app.state.hub
    return hub


HubDep = Annotated[Hub, Depends(get_hub)]
