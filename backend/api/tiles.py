"""Offline tile sets: the list, and their tiles at ``/tiles/<name>/{z}/{x}/{y}``.

Tiles are behind the same login as the rest (the dashboard's cookie goes with every
``<img>``). A tile URL carries the set's version (``?v=``), which changes when the file
does, so the browser may keep a tile for a long time: ``private`` because it was served
to a logged-in user, with an ETag for the revalidation after that.
"""

from __future__ import annotations

import asyncio
import hashlib
from typing import Annotated

from fastapi import Path, Query, Request, Response
from pydantic import BaseModel, Field

from backend.api.deps import TilesDep
from backend.api.security import SecuredRouter, requires
from backend.auth.policy import Permission
from backend.errors import InvalidRequest, NotFound
from backend.mapping.tiles import MAX_ZOOM, TileLibrary, TileSetInfo, UnknownTileSet

# Under /api/v1: the list of sets. At the root: the tiles, a path every tile client knows.
router = SecuredRouter(tags=["tiles"])
tile_router = SecuredRouter(tags=["tiles"])

TILE_PATH = "/tiles/{name}/{z}/{x}/{y}"
# A tile asked for with the set's current version never changes; without it, an hour.
CACHE_VERSIONED = "private, max-age=31536000, immutable"
CACHE_UNVERSIONED = "private, max-age=3600"
CACHE_MISSING = "private, max-age=3600"  # a sparse set: do not ask again on every pan


class TileSet(BaseModel):
    name: str = Field(description="the file name without .mbtiles or .pmtiles")
    kind: str = Field(description="mbtiles or pmtiles")
    media_type: str
    min_zoom: int
    max_zoom: int
    bounds: tuple[float, float, float, float] | None = Field(
        description="west, south, east, north in degrees, when the file says"
    )
    attribution: str
    url: str = Field(description="the tile URL template, with the set's version")

    @classmethod
    def of(cls, info: TileSetInfo) -> TileSet:
        return cls(
            name=info.name,
            kind=info.kind,
            media_type=info.media_type,
            min_zoom=info.min_zoom,
            max_zoom=info.max_zoom,
            bounds=info.bounds,
            attribution=info.attribution,
            url=f"/tiles/{info.name}/{{z}}/{{x}}/{{y}}?v={info.version}",
        )


async def tile_sets(tiles: TileLibrary) -> list[TileSet]:
    return [TileSet.of(info) for info in await asyncio.to_thread(tiles.sets)]


@router.get("/tiles", response_model=list[TileSet], openapi_extra=requires(Permission.READ))
async def list_tile_sets(tiles: TilesDep) -> list[TileSet]:
    """The offline tile sets in the hub's tiles folder (``<data dir>/tiles``)."""
    return await tile_sets(tiles)


@tile_router.get(
    TILE_PATH,
    openapi_extra=requires(Permission.READ),
    response_class=Response,
    # Beside the API, as the dashboard's files are: the list above documents the sets.
    include_in_schema=False,
)
async def get_tile(
    tiles: TilesDep,
    request: Request,
    name: Annotated[str, Path(pattern=r"^[A-Za-z0-9][A-Za-z0-9_.-]{0,63}$")],
    z: Annotated[int, Path(ge=0, le=MAX_ZOOM)],
    x: Annotated[int, Path(ge=0)],
    y: Annotated[int, Path(ge=0)],
    v: Annotated[str | None, Query(max_length=32, description="the set's version")] = None,
) -> Response:
    """One tile of an offline set, in XYZ order (y from the north, as web maps count)."""
    for field, value in (("x", x), ("y", y)):
        if value >= 2**z:
            raise InvalidRequest(field, f"{field} must be below 2**z ({2**z})", location="path")
    try:
        info, data = await asyncio.to_thread(tiles.tile, name, z, x, y)
    except UnknownTileSet:
        raise NotFound(f"no tile set named {name!r}") from None
    if data is None:
        return Response(status_code=404, headers={"Cache-Control": CACHE_MISSING})
    etag = '"' + hashlib.blake2s(data, digest_size=12).hexdigest() + '"'
    cache = CACHE_VERSIONED if v == info.version else CACHE_UNVERSIONED
    headers = {"Cache-Control": cache, "ETag": etag}
    if etag in request.headers.get("if-none-match", ""):
        return Response(status_code=304, headers=headers)
    return Response(data, media_type=info.media_type, headers=headers)
