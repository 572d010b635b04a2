"""Survey photos: the agents' resumable uploads, the counts per drone, the zip export.

``PUT /vehicles/{vehicle_id}/photos/{photo_id}?offset=N`` takes one chunk (the body, at
most GCS_MAX_BODY_BYTES; the agent sends 256 KiB) at byte ``offset``; the first chunk
carries the photo's metadata (protocol.photos.PhotoMeta, JSON) in ``X-Photo-Meta``.
``GET`` on the same address says how much the hub has, so a cut upload resumes there.
Only the vehicle's own agent token may upload (the policy's choke point refuses another
vehicle's token; that refusal is counted as well). A refusal says why and is counted per
drone: no pose, a pose far from its survey, a corrupt or truncated JPEG, an image that
is not the camera model's size, more bytes than a photo may have.
"""

from __future__ import annotations

import asyncio
import contextlib
from collections import Counter, defaultdict
from collections.abc import Callable, Coroutine
from pathlib import Path as FilePath
from typing import Annotated, Any

from fastapi import Header, Path, Query, Request, status
from fastapi.responses import FileResponse, JSONResponse
from pydantic import AfterValidator, BaseModel, Field
from starlette.background import BackgroundTask
from starlette.responses import Response

from backend.api.deps import RegistryDep
from backend.api.finite_json import FiniteJsonRoute
from backend.api.security import SecuredRouter, requires
from backend.auth.policy import Permission
from backend.errors import Forbidden
from backend.imagery.photos.checks import Refusal, Refused
from backend.imagery.photos.deps import PhotosDep, get_photos
from backend.imagery.photos.export import write_zip
from backend.imagery.photos.repository import PhotoCount
from backend.imagery.photos.uploads import OffsetMismatch
from backend.survey.deps import SurveysDep
from backend.survey.routes import SurveyIdPath
from protocol.messages import VehicleId
from protocol.photos import MAX_PHOTO_BYTES, PhotoId


def _not_a_dot_name(photo_id: str) -> str:
    # The id's pattern allows dots; "." and ".." would name a folder, not a file.
    if photo_id in (".", ".."):
        raise ValueError("a photo id cannot be '.' or '..'")
    return photo_id


PhotoIdPath = Annotated[PhotoId, AfterValidator(_not_a_dot_name), Path()]


class _CountsOtherVehicleTokens(FiniteJsonRoute):
    """The policy refuses an agent token of another vehicle before the route runs; the
    refusal is counted here too, against the vehicle it tried to upload for."""

    def get_route_handler(self) -> Callable[[Request], Coroutine[Any, Any, Response]]:
        handler = super().get_route_handler()

        async def counting_handler(request: Request) -> Response:
            try:
                return await handler(request)
            except Forbidden:
                principal = getattr(request.state, "principal", None)
                vehicle_id = request.path_params.get("vehicle_id")
                if principal is not None and principal.is_agent and vehicle_id is not None:
                    get_photos(request).count_unrecorded(vehicle_id, Refusal.OTHER_VEHICLE)
                raise

        return counting_handler


router = SecuredRouter(tags=["photos"], route_class=_CountsOtherVehicleTokens)


class UploadStatus(BaseModel):
    received: int = Field(description="bytes the hub has committed; the next chunk's offset")
    size: int | None = Field(default=None, description="the photo's size, once declared")
    state: str = Field(description="receiving, stored or refused")
    reason: str | None = Field(default=None, description="why it was refused")


def _refusal(refusal: Refused) -> JSONResponse:
    return JSONResponse(
        {"detail": refusal.reason, "code": refusal.code.value}, status_code=refusal.status
    )


@router.put(
    "/vehicles/{vehicle_id}/photos/{photo_id}",
    response_model=UploadStatus,
    openapi_extra=requires(Permission.AGENT),
    responses={
        201: {"description": "The last chunk: the photo is checked and stored"},
        409: {"description": "Wrong offset: the body's `received` is where to go on"},
        413: {"description": "More bytes than declared or than a photo may have"},
        422: {"description": "Refused for good, with the reason and its `code`"},
    },
)
async def upload_photo_chunk(
    vehicle_id: Annotated[VehicleId, Path()],
    photo_id: PhotoIdPath,
    request: Request,
    photos: PhotosDep,
    vehicles: RegistryDep,
    offset: Annotated[int, Query(ge=0, le=MAX_PHOTO_BYTES)] = 0,
    x_photo_meta: Annotated[str | None, Header(max_length=8192)] = None,
) -> Response:
    """One chunk of a photo at byte ``offset`` (the body: raw JPEG bytes)."""
    vehicles.get(vehicle_id)
    chunk = await request.body()
    try:
        state = await photos.put_chunk(vehicle_id, photo_id, offset, chunk, x_photo_meta)
    except OffsetMismatch as mismatch:
        return JSONResponse(
            {"detail": str(mismatch), "received": mismatch.received},
            status_code=status.HTTP_409_CONFLICT,
        )
    except Refused as refusal:
        return _refusal(refusal)
    stored_now = state.state == "stored" and state.received == state.size and chunk
    code = status.HTTP_201_CREATED if stored_now else status.HTTP_200_OK
    return JSONResponse(state.body(), status_code=code)


@router.get(
    "/vehicles/{vehicle_id}/photos/{photo_id}",
    response_model=UploadStatus,
    openapi_extra=requires(Permission.AGENT),
)
async def photo_upload_status(
    vehicle_id: Annotated[VehicleId, Path()],
    photo_id: PhotoIdPath,
    photos: PhotosDep,
    vehicles: RegistryDep,
) -> UploadStatus:
    """How much of the photo the hub has (404: nothing yet), to resume a cut upload."""
    vehicles.get(vehicle_id)
    return UploadStatus(**(await photos.state(vehicle_id, photo_id)).body())


class DronePhotos(BaseModel):
    vehicle_id: str
    received: int = Field(description="photos stored")
    failed: int = Field(description="photos refused")
    reasons: dict[str, int] = Field(description="refusals by reason code")


class SurveyPhotos(BaseModel):
    survey_id: str
    drones: list[DronePhotos]
    photos: list[dict[str, Any]] = Field(description="each stored photo: id, vehicle, pose")


@router.get(
    "/surveys/{survey_id}/photos",
    response_model=SurveyPhotos,
    openapi_extra=requires(Permission.READ),
)
async def survey_photos(
    survey_id: SurveyIdPath,
    photos: PhotosDep,
    surveys: SurveysDep,
    limit: Annotated[int, Query(ge=0, le=100_000)] = 1000,
) -> SurveyPhotos:
    """Photos received and refused per drone (with the reasons), and the stored ones."""
    run = await surveys.find(survey_id)
    counts = await asyncio.to_thread(photos.repository.counts, survey_id)
    by_drone = _tally(counts, photos.unrecorded)
    vehicles = [d.vehicle_id for d in run.drones]
    vehicles += sorted({row.vehicle_id for row in counts} - set(vehicles))
    stored = await asyncio.to_thread(photos.repository.of_survey, survey_id)
    return SurveyPhotos(
        survey_id=survey_id,
        drones=[
            by_drone.get(v, DronePhotos(vehicle_id=v, received=0, failed=0, reasons={}))
            for v in vehicles
        ],
        photos=[photos.summary(record) for record in stored[:limit]],
    )


class VehiclePhotos(DronePhotos):
    photos: list[dict[str, Any]] = Field(
        description="its newest photos, stored and refused: id, state, reason, pose"
    )


@router.get(
    "/vehicles/{vehicle_id}/photos",
    response_model=VehiclePhotos,
    openapi_extra=requires(Permission.READ),
)
async def vehicle_photos(
    vehicle_id: Annotated[VehicleId, Path()],
    photos: PhotosDep,
    vehicles: RegistryDep,
    limit: Annotated[int, Query(ge=0, le=10_000)] = 100,
) -> VehiclePhotos:
    """One vehicle's photos, whatever their survey: counts with reasons, the newest."""
    vehicles.get(vehicle_id)
    counts = await asyncio.to_thread(photos.repository.vehicle_counts, vehicle_id)
    tally = _tally(counts, photos.unrecorded).get(vehicle_id)
    records = await asyncio.to_thread(photos.repository.of_vehicle, vehicle_id, limit)
    return VehiclePhotos(
        vehicle_id=vehicle_id,
        received=tally.received if tally else 0,
        failed=tally.failed if tally else 0,
        reasons=tally.reasons if tally else {},
        photos=[photos.summary(record) for record in records],
    )


def _tally(
    counts: list[PhotoCount], unrecorded: Counter[tuple[str, str]]
) -> dict[str, DronePhotos]:
    """Stored and refused photos per vehicle (refusals by their reason's code), with the
    refusals no row records (another vehicle's token) for the vehicles in ``counts``'s
    scope and those."""
    received: Counter[str] = Counter()
    reasons: defaultdict[str, Counter[str]] = defaultdict(Counter)
    for row in counts:
        if row.state == "stored":
            received[row.vehicle_id] += row.count
        else:
            reasons[row.vehicle_id][(row.reason or "refused").split(":")[0]] += row.count
    for (vehicle_id, code), count in unrecorded.items():
        reasons[vehicle_id][code] += count
    return {
        v: DronePhotos(
            vehicle_id=v,
            received=received[v],
            failed=sum(reasons[v].values()),
            reasons=dict(reasons[v]),
        )
        for v in set(received) | set(reasons)
    }


@router.get(
    "/surveys/{survey_id}/photos.zip",
    response_class=FileResponse,
    openapi_extra=requires(Permission.READ),
    responses={200: {"content": {"application/zip": {}}}},
)
async def export_survey_photos(
    survey_id: SurveyIdPath, photos: PhotosDep, surveys: SurveysDep
) -> FileResponse:
    """The survey's geotagged photos for OpenDroneMap: ``images/``, ``image_list.txt``
    and ``geo.txt`` in one zip."""
    await surveys.find(survey_id)
    records = await asyncio.to_thread(photos.repository.of_survey, survey_id)
    folder = photos.root / ".exports"  # the ingest's root is the hub's photos folder
    path = await asyncio.to_thread(write_zip, records, folder)
    return FileResponse(
        path,
        media_type="application/zip",
        filename=f"survey-{survey_id}-photos.zip",
        background=BackgroundTask(_remove, path),
    )


def _remove(path: FilePath) -> None:
    with contextlib.suppress(FileNotFoundError):
        path.unlink()
