"""The live orthomosaic of each survey: its progress and coverage, and its tiles.

Tiles are at ``/api/v1/mosaics/{survey_id}/tiles/{z}/{x}/{y}`` (XYZ, y from the north):
under the API rather than beside the offline sets' ``/tiles/{name}/...``, because a
mosaic is named by its survey, not by a file, and changes while the survey flies. Each
tile carries its version (``ETag``, ``X-Tile-Version``) and is revalidated on every use
(``no-cache``): the browser keeps it, and asks again with ``If-None-Match`` for a 304 until
a photo changes it. A tile outside the mosaic is a 404.
"""

from __future__ import annotations

import asyncio
from typing import Annotated, Literal

from fastapi import Path, Request, Response
from fastapi.responses import FileResponse, JSONResponse
from pydantic import Field

from backend.api.deps import TilesDep
from backend.api.responses import ErrorMessage
from backend.api.security import SecuredRouter, requires
from backend.api.tiles import TileSet
from backend.auth.policy import Permission
from backend.errors import Conflict, InvalidRequest, NotFound
from backend.imagery.mosaic.deps import MosaicsDep
from backend.imagery.mosaic.export import FORMATS, ExportError
from backend.imagery.mosaic.progress import MosaicProgress
from backend.imagery.mosaic.service import SURVEY_ID, MosaicService, UnknownMosaic
from backend.mapping.tiles import MAX_ZOOM

router = SecuredRouter(tags=["mosaics"])

SurveyIdPath = Annotated[str, Path(pattern=SURVEY_ID.pattern, description="the survey's id")]
CACHE_TILE = "private, no-cache"  # kept, but asked again each time: the mosaic grows
CACHE_MISSING = "private, max-age=5"  # not there yet; it may be in a few seconds


class MosaicDetail(MosaicProgress):
    tile_url: str = Field(description="the tile URL template ({z}/{x}/{y}) of this mosaic")


def _progress(mosaic: MosaicService, survey_id: str) -> MosaicDetail:
    try:
        progress = mosaic.progress(survey_id)
    except UnknownMosaic:
        raise NotFound(f"no photo of survey {survey_id} has reached the mosaic") from None
    return MosaicDetail(
        **progress.model_dump(), tile_url=f"/api/v1/mosaics/{survey_id}/tiles/{{z}}/{{x}}/{{y}}"
    )


@router.get("/mosaics", response_model=list[MosaicDetail], openapi_extra=requires(Permission.READ))
async def list_mosaics(mosaics: MosaicsDep) -> list[MosaicDetail]:
    """Every survey mosaic the hub holds, with its progress."""
    return [_progress(mosaics, survey_id) for survey_id in mosaics.surveys()]


@router.get(
    "/mosaics/{survey_id}",
    response_model=MosaicDetail,
    openapi_extra=requires(Permission.READ),
    responses={404: {"description": "No photo of this survey has reached the mosaic"}},
)
async def get_mosaic(survey_id: SurveyIdPath, mosaics: MosaicsDep) -> MosaicDetail:
    """Photos processed and failed (each failure's reason), per vehicle too; the coverage
    of the survey's area in percent and as a GeoJSON outline; the zoom range and bounds."""
    return _progress(mosaics, survey_id)


@router.get(
    "/mosaics/{survey_id}/export.{kind}",
    openapi_extra=requires(Permission.READ),
    response_class=FileResponse,
    responses={
        200: {"content": {media_type: {} for media_type in FORMATS.values()}},
        404: {"description": "No photo of this survey has reached the mosaic"},
        409: {"description": "The mosaic has no tiles yet", "model": ErrorMessage},
    },
)
async def export_mosaic(
    survey_id: SurveyIdPath, kind: Literal["tif", "mbtiles", "pmtiles"], mosaics: MosaicsDep
) -> FileResponse:
    """The mosaic as a file: `tif` a Cloud-Optimised GeoTIFF (EPSG:3857, RGBA, at the
    native zoom), `mbtiles` or `pmtiles` every zoom's tiles as PNG (drop either in the
    hub's tiles folder to use it as an offline base map)."""
    try:
        path = await asyncio.to_thread(mosaics.export, survey_id, kind)
    except UnknownMosaic:
        raise NotFound(f"no photo of survey {survey_id} has reached the mosaic") from None
    except ExportError as error:
        raise Conflict(str(error)) from None
    return FileResponse(path, media_type=FORMATS[kind], filename=f"mosaic-{survey_id}.{kind}")


@router.post(
    "/mosaics/{survey_id}/basemap",
    response_model=TileSet,
    openapi_extra=requires(Permission.COMMAND),
    responses={
        404: {"description": "No photo of this survey has reached the mosaic"},
        409: {"description": "The mosaic has no tiles yet", "model": ErrorMessage},
    },
)
async def install_basemap(survey_id: SurveyIdPath, mosaics: MosaicsDep, tiles: TilesDep) -> TileSet:
    """Put the mosaic in the hub's offline tiles folder as `mosaic-<survey_id>.pmtiles`:
    the dashboard then offers it as a base map, with no internet (done again, it is
    replaced by the mosaic as it is now)."""
    try:
        name = await asyncio.to_thread(mosaics.install_basemap, survey_id, tiles.folder)
    except UnknownMosaic:
        raise NotFound(f"no photo of survey {survey_id} has reached the mosaic") from None
    except ExportError as error:
        raise Conflict(str(error)) from None
    sets = await asyncio.to_thread(tiles.sets)
    installed = next((info for info in sets if info.name == name), None)
    if installed is None:
        raise Conflict(f"the tiles folder did not take {name}.pmtiles; see the hub's log")
    return TileSet.of(installed)


@router.get(
    "/mosaics/{survey_id}/tiles/{z}/{x}/{y}",
    openapi_extra=requires(Permission.READ),
    response_class=Response,
    responses={
        200: {"content": {"image/jpeg": {}, "image/png": {}}},
        304: {"description": "The tile has not changed since the ETag given"},
        404: {"description": "No such mosaic, or no tile there"},
    },
)
async def get_mosaic_tile(
    mosaics: MosaicsDep,
    request: Request,
    survey_id: SurveyIdPath,
    z: Annotated[int, Path(ge=0, le=MAX_ZOOM)],
    x: Annotated[int, Path(ge=0)],
    y: Annotated[int, Path(ge=0)],
) -> Response:
    """One tile: JPEG where the photos cover all of it, PNG (transparent where they do
    not) at the mosaic's edges."""
    for field, value in (("x", x), ("y", y)):
        if value >= 2**z:
            raise InvalidRequest(field, f"{field} must be below 2**z ({2**z})", location="path")
    try:
        served = await asyncio.to_thread(mosaics.tile, survey_id, z, x, y)
    except UnknownMosaic:
        raise NotFound(f"no photo of survey {survey_id} has reached the mosaic") from None
    if served is None:
        # The documented error body, and a short cache: the tile may come with a photo.
        return JSONResponse(
            {"detail": f"no tile {z}/{x}/{y} in the mosaic of survey {survey_id} (yet)"},
            status_code=404,
            headers={"Cache-Control": CACHE_MISSING},
        )
    etag = f'"{survey_id}-{z}-{x}-{y}-{served.version}"'
    headers = {"Cache-Control": CACHE_TILE, "ETag": etag, "X-Tile-Version": str(served.version)}
    if etag in request.headers.get("if-none-match", ""):
        return Response(status_code=304, headers=headers)
    return Response(served.data, media_type=served.media_type, headers=headers)
