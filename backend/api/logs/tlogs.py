"""The .tlogs agents record on board: uploaded within a quota, listed, downloaded."""

from __future__ import annotations

import asyncio
import re
import time
from pathlib import Path as FilePath
from typing import Annotated, BinaryIO

from fastapi import Path, Request, status
from fastapi.responses import FileResponse
from pydantic import BaseModel, ConfigDict

from backend.api.deps import LogbookDep, RegistryDep, SettingsDep
from backend.api.logs.common import MAX_ID
from backend.api.security import SecuredRouter, requires
from backend.auth.policy import Permission
from backend.errors import InvalidRequest, QuotaExceeded
from backend.storage.tlog_check import InvalidTlog, TlogChecker
from protocol.messages import VehicleId

router = SecuredRouter(tags=["flight log"])

SAFE_FILENAME = re.compile(r"[^A-Za-z0-9_.-]")


class Tlog(BaseModel):
    model_config = ConfigDict(from_attributes=True)

    id: int
    vehicle_id: str
    filename: str
    size: int
    uploaded_at: float


@router.post(
    "/vehicles/{vehicle_id}/tlogs",
    response_model=Tlog,
    status_code=status.HTTP_201_CREATED,
    openapi_extra=requires(Permission.AGENT),
)
async def upload_tlog(
    vehicle_id: Annotated[VehicleId, Path()],
    request: Request,
    registry: RegistryDep,
    logbook: LogbookDep,
    settings: SettingsDep,
) -> Tlog:
    """An agent uploads the .tlog it recorded on board (body: the raw file).

    The body must be a .tlog (timestamped MAVLink frames: 422 otherwise, at the first
    record that is not), and fit the vehicle's quota (``max_tlog_bytes_per_vehicle``
    over all its files: 413 otherwise; ``max_tlog_bytes`` bounds one file)."""
    registry.get(vehicle_id)
    quota = settings.max_tlog_bytes_per_vehicle
    stored = sum(row.size for row in await asyncio.to_thread(logbook.tlogs, vehicle_id))
    if stored >= quota:
        raise QuotaExceeded(_quota_used(vehicle_id, stored, quota))
    name = SAFE_FILENAME.sub("_", request.headers.get("x-filename", "flight.tlog"))[:100]
    folder = settings.data_dir / "tlogs" / vehicle_id
    await asyncio.to_thread(folder.mkdir, parents=True, exist_ok=True)
    target = folder / f"{time.time_ns()}_{name}"
    size = 0
    checker = TlogChecker()
    try:
        with target.open("xb") as file:  # streamed to disk chunk by chunk
            async for chunk in request.stream():
                size += len(chunk)
                if stored + size > quota:
                    raise QuotaExceeded(_quota_used(vehicle_id, stored, quota))
                await asyncio.to_thread(_check_and_write, checker, file, chunk)
        checker.finish()
    except InvalidTlog as error:
        target.unlink(missing_ok=True)
        raise InvalidRequest("body", str(error)) from None
    except BaseException:
        target.unlink(missing_ok=True)  # no half files from a cut upload
        raise
    tlog_id = await asyncio.to_thread(logbook.add_tlog, vehicle_id, name, str(target), size)
    return Tlog.model_validate(await asyncio.to_thread(logbook.tlog, tlog_id))


def _check_and_write(checker: TlogChecker, file: BinaryIO, chunk: bytes) -> None:
    checker.feed(chunk)  # before the write: nothing that is not a .tlog is kept
    file.write(chunk)


def _quota_used(vehicle_id: str, stored: int, quota: int) -> str:
    return (
        f"this upload would take {vehicle_id}'s stored .tlogs over their quota of "
        f"{quota} bytes ({stored} bytes stored); ask an admin to remove old ones"
    )


@router.get(
    "/vehicles/{vehicle_id}/tlogs",
    response_model=list[Tlog],
    openapi_extra=requires(Permission.READ),
)
async def list_tlogs(
    vehicle_id: Annotated[VehicleId, Path()], registry: RegistryDep, logbook: LogbookDep
) -> list[Tlog]:
    registry.get(vehicle_id)
    return [Tlog.model_validate(row) for row in await asyncio.to_thread(logbook.tlogs, vehicle_id)]


@router.get(
    "/tlogs/{tlog_id}",
    response_class=FileResponse,
    openapi_extra=requires(Permission.READ),
    responses={200: {"content": {"application/octet-stream": {}}}},
)
async def download_tlog(
    tlog_id: Annotated[int, Path(ge=1, le=MAX_ID)], logbook: LogbookDep
) -> FileResponse:
    row = await asyncio.to_thread(logbook.tlog, tlog_id)
    return FileResponse(
        FilePath(row.path), filename=row.filename, media_type="application/octet-stream"
    )
