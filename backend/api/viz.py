"""The 3D view under /viz/: viser's page and its scene WebSocket, behind the hub's login.

Every request is checked by ``backend.viz3d.gateway`` before anything reaches viser. The
routes stay out of the OpenAPI document: they carry viser's own page and wire format.
"""

from __future__ import annotations

from fastapi import APIRouter, Request, WebSocket
from fastapi.responses import RedirectResponse, Response

from backend.api.deps import VizServicesDep
from backend.viz3d.gateway import Refusal, VizRelay, admit, forward_http, refusal_response

VIZ_PREFIX = "/viz"

router = APIRouter(include_in_schema=False)


@router.get(VIZ_PREFIX)
async def viz_root(request: Request, viz: VizServicesDep) -> Response:
    # viser's client derives its WebSocket address from the page's, so the page must be
    # /viz/ (with the slash) for the socket to be /viz/ too.
    try:
        await admit(request, viz)
    except Refusal as refusal:
        return refusal_response(refusal)
    return RedirectResponse(VIZ_PREFIX + "/", status_code=307)


@router.api_route(VIZ_PREFIX + "/{path:path}", methods=["GET", "HEAD"])
async def viz_files(request: Request, viz: VizServicesDep, path: str) -> Response:
    return await forward_http(request, viz, path)


@router.websocket(VIZ_PREFIX)
@router.websocket(VIZ_PREFIX + "/{path:path}")
async def viz_socket(websocket: WebSocket, viz: VizServicesDep) -> None:
    await VizRelay(websocket, viz).serve()
