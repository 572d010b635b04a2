"""Resumable photo uploads: chunks at an offset, checked, stored once, counted.

An upload in progress is a ``.part`` file and its metadata (``.json``) under
``<photos>/.partial/<vehicle>/``, so a hub restarted mid-upload resumes it too: the
committed offset is the ``.part`` file's size. The first chunk brings the metadata
(protocol.photos.PhotoMeta); the pose and the survey are checked then, before megabytes
follow. After the last chunk the image is checked (a whole JPEG of the camera's size),
moved to ``<photos>/<vehicle>/<photo id>.jpg``, recorded, and handed to the sink (the
live mosaic). A refusal is recorded too, with its reason, so it is counted once per
photo however often the agent retries, and asked again it answers the same.

An upload's files are ``uploads.py``'s; the first chunk's metadata and the survey a photo
belongs to, ``metadata.py``'s; this module keeps the order of the steps and the locks.
"""

from __future__ import annotations

import asyncio
import json
import logging
import os
import time
from collections import Counter
from pathlib import Path
from typing import Any

from pydantic import ValidationError

from backend.errors import NotFound
from backend.imagery.photos.checks import Refusal, Refused, check_against_survey, check_image
from backend.imagery.photos.metadata import ActiveSurveys, FindSurvey, SurveyOfPhoto, parse_meta
from backend.imagery.photos.partials import PartialLimits, in_progress, stale
from backend.imagery.photos.repository import PhotoRecord, PhotoRepository
from backend.imagery.photos.stored import PhotoSink, StoredPhoto
from backend.imagery.photos.uploads import (
    PARTIAL_DIR,
    REFUSED,
    STORED,
    OffsetMismatch,
    UploadState,
    append,
    discard,
    final_path,
    partial_paths,
    size_of,
)
from backend.survey.flight.run import SurveyRun
from protocol.photos import PhotoMeta

__all__ = ["OffsetMismatch", "PhotoIngest", "UploadState"]

log = logging.getLogger(__name__)


class PhotoIngest:
    def __init__(
        self,
        repository: PhotoRepository,
        root: Path,
        active_surveys: ActiveSurveys,
        find_survey: FindSurvey,
        *,
        margin_m: float,
        quota_bytes: int,
        partials: PartialLimits | None = None,
        sink: PhotoSink | None = None,
    ) -> None:
        self.repository = repository
        self.root = root
        self._survey_of = SurveyOfPhoto(active_surveys, find_survey)
        self.margin_m = margin_m
        self.quota_bytes = quota_bytes
        self.partials = partials or PartialLimits()
        self.sink = sink
        self._locks: dict[tuple[str, str], asyncio.Lock] = {}
        # Held while a vehicle's new upload is admitted: two first chunks at once must
        # not both fit in the room that only one of them has.
        self._admissions: dict[str, asyncio.Lock] = {}
        # Refusals with no row of their own (another vehicle's token: no row is written
        # for a caller who may not speak for that vehicle), by (vehicle, code).
        self.unrecorded: Counter[tuple[str, str]] = Counter()

    def _partial(self, vehicle_id: str, photo_id: str) -> tuple[Path, Path]:
        return partial_paths(self.root, vehicle_id, photo_id)

    def _lock(self, vehicle_id: str, photo_id: str) -> asyncio.Lock:
        return self._locks.setdefault((vehicle_id, photo_id), asyncio.Lock())

    # -- asking ----------------------------------------------------------------------

    async def state(self, vehicle_id: str, photo_id: str) -> UploadState:
        """NotFound when the hub has nothing of that photo."""
        record = await asyncio.to_thread(self.repository.get, vehicle_id, photo_id)
        if record is not None:
            return UploadState(
                record.size if record.state == STORED else 0,
                record.size,
                record.state,
                record.reason,
            )
        part, meta_path = self._partial(vehicle_id, photo_id)
        try:
            meta = PhotoMeta.model_validate_json(await asyncio.to_thread(meta_path.read_bytes))
            received = (await asyncio.to_thread(part.stat)).st_size
        except (OSError, ValidationError):
            raise NotFound(f"no upload of photo {photo_id} from {vehicle_id}") from None
        return UploadState(received, meta.size_bytes, "receiving")

    # -- receiving -------------------------------------------------------------------

    async def put_chunk(
        self, vehicle_id: str, photo_id: str, offset: int, chunk: bytes, meta_json: str | None
    ) -> UploadState:
        """Take one chunk at ``offset``. Raises OffsetMismatch (the hub's offset) or
        Refused (recorded, with its reason)."""
        async with self._lock(vehicle_id, photo_id):
            record = await asyncio.to_thread(self.repository.get, vehicle_id, photo_id)
            if record is not None:
                if record.state == REFUSED:  # asked again, answered the same
                    reason = record.reason or "bad_metadata: refused"
                    code = Refusal(reason.split(":")[0])
                    raise Refused(code, reason, 413 if code is Refusal.TOO_LARGE else 422)
                return UploadState(record.size, record.size, STORED)  # idempotent
            part, meta_path = self._partial(vehicle_id, photo_id)
            if offset == 0:
                meta = await self._begin(vehicle_id, photo_id, meta_json, part, meta_path)
            else:
                try:
                    meta = PhotoMeta.model_validate_json(
                        await asyncio.to_thread(meta_path.read_bytes)
                    )
                except (OSError, ValidationError):
                    raise OffsetMismatch(0) from None  # nothing here: start again
            received = await asyncio.to_thread(size_of, part)
            if offset != received:
                raise OffsetMismatch(received)
            if received + len(chunk) > meta.size_bytes:
                await self._refuse(
                    vehicle_id,
                    photo_id,
                    meta,
                    Refusal.TOO_LARGE,
                    f"{received + len(chunk)} bytes sent, more than the {meta.size_bytes} "
                    "the metadata declared",
                    status=413,
                )
            await asyncio.to_thread(append, part, chunk)
            received += len(chunk)
            if received < meta.size_bytes:
                return UploadState(received, meta.size_bytes, "receiving")
            await self._finish(vehicle_id, meta, part)
            # Done: its lock is not needed again (a late duplicate finds the row and makes
            # a lock of its own), so the locks held stay one per upload in progress.
            self._locks.pop((vehicle_id, photo_id), None)
            return UploadState(received, meta.size_bytes, STORED)

    async def _begin(
        self, vehicle_id: str, photo_id: str, meta_json: str | None, part: Path, meta_path: Path
    ) -> PhotoMeta:
        """Check what can be checked before the image comes; refusals are recorded, but
        for the quota, which an admin may free."""
        meta: PhotoMeta | None = None
        run: SurveyRun | None = None
        try:
            meta = parse_meta(photo_id, meta_json)
            run = await self.survey_of(vehicle_id, meta)
            if run is not None:
                check_against_survey(meta.pose, meta.camera, run, self.margin_m)
        except Refused as refusal:
            await self._refuse(
                vehicle_id,
                photo_id,
                meta,
                refusal.code,
                refusal.reason,
                survey_id=run.id if run is not None else None,
                status=refusal.status,
            )
        assert meta is not None
        if run is not None and meta.survey_id is None:
            meta = meta.model_copy(update={"survey_id": run.id})
        async with self._admissions.setdefault(vehicle_id, asyncio.Lock()):
            await self._admit(vehicle_id, meta, part.parent)
            await asyncio.to_thread(part.parent.mkdir, parents=True, exist_ok=True)
            await asyncio.to_thread(part.write_bytes, b"")  # a new start discards the old
            await asyncio.to_thread(meta_path.write_text, meta.model_dump_json())
        return meta

    async def _admit(self, vehicle_id: str, meta: PhotoMeta, folder: Path) -> None:
        """Room for one more upload of this vehicle: under its count of uploads at once,
        and its stored photos, the sizes its other uploads in progress declared and this
        one's within the quota. Neither refusal is recorded: both pass as uploads end
        (or expire), or as an admin frees the quota."""
        cutoff = time.time() - self.partials.expiry_s
        others = []
        for upload in await asyncio.to_thread(in_progress, folder):
            if upload.photo_id == meta.photo_id:
                continue
            # Its own stale ones go now, not at the next sweep: they hold its room.
            if upload.touched < cutoff and await self._expire(vehicle_id, upload.photo_id):
                continue
            others.append(upload)
        limit = self.partials.max_per_vehicle
        if len(others) >= limit:
            raise Refused(
                Refusal.UPLOADS_IN_PROGRESS,
                f"{vehicle_id} has {len(others)} photo uploads in progress, the most a "
                f"vehicle may have at once ({limit}); finish one first",
                status=429,
            )
        stored = await asyncio.to_thread(self.repository.stored_bytes, vehicle_id)
        reserved = sum(upload.reserved_bytes for upload in others)
        if stored + reserved + meta.size_bytes > self.quota_bytes:
            raise Refused(
                Refusal.QUOTA,
                f"{vehicle_id}'s photos would pass their quota of {self.quota_bytes} bytes "
                f"({stored} stored, {reserved} reserved by {len(others)} uploads in progress)",
                status=413,
            )

    async def run(self) -> None:
        """Give up uploads left untouched for ``partials.expiry_s`` (an agent that never
        came back for them); until then a vehicle's quota holds their room."""
        expiry_s = self.partials.expiry_s
        while True:
            await self.expire_stale()
            await asyncio.sleep(min(expiry_s / 4, 600.0))

    async def expire_stale(self, now: float | None = None) -> int:
        """Remove the uploads untouched for ``partials.expiry_s``; how many went."""
        found = await asyncio.to_thread(stale, self.root / PARTIAL_DIR, self.partials.expiry_s, now)
        return sum([await self._expire(vehicle, photo) for vehicle, photo in found])

    async def _expire(self, vehicle_id: str, photo_id: str) -> bool:
        """Remove one stale upload, unless a chunk of it is arriving right now."""
        lock = self._lock(vehicle_id, photo_id)
        if lock.locked():
            return False
        async with lock:
            part, meta_path = self._partial(vehicle_id, photo_id)
            await asyncio.to_thread(discard, part, meta_path)
        self._locks.pop((vehicle_id, photo_id), None)
        log.info("photo upload %s from %s expired unfinished", photo_id, vehicle_id)
        return True

    async def survey_of(
        self, vehicle_id: str, meta: PhotoMeta, now: float | None = None
    ) -> SurveyRun | None:
        """The survey the photo belongs to (``metadata.SurveyOfPhoto``)."""
        return await self._survey_of(vehicle_id, meta, now)

    async def _finish(self, vehicle_id: str, meta: PhotoMeta, part: Path) -> None:
        try:
            await asyncio.to_thread(check_image, part, meta.camera)
        except Refused as refusal:
            await self._refuse(
                vehicle_id,
                meta.photo_id,
                meta,
                refusal.code,
                refusal.reason,
                survey_id=meta.survey_id,
            )
        final = final_path(self.root, vehicle_id, meta.photo_id)
        await asyncio.to_thread(final.parent.mkdir, parents=True, exist_ok=True)
        await asyncio.to_thread(os.replace, part, final)
        record = PhotoRecord(
            vehicle_id,
            meta.photo_id,
            meta.survey_id,
            STORED,
            None,
            time.time(),
            str(final),
            meta.size_bytes,
            meta.model_dump_json(),
        )
        await asyncio.to_thread(self.repository.add, record)
        await asyncio.to_thread(discard, part.with_suffix(".json"))
        log.info("photo %s from %s stored (%d bytes)", meta.photo_id, vehicle_id, meta.size_bytes)
        if self.sink is not None and meta.survey_id is not None:
            photo = StoredPhoto(
                meta.photo_id, vehicle_id, meta.survey_id, final, meta.pose, meta.camera
            )
            try:
                await self.sink.add_photo(photo)
            except Exception:
                # The photo is stored and counted; a sink's failure must not undo that.
                log.exception("the photo sink failed on %s", meta.photo_id)

    async def _refuse(
        self,
        vehicle_id: str,
        photo_id: str,
        meta: PhotoMeta | None,
        code: Refusal,
        reason: str,
        *,
        survey_id: str | None = None,
        status: int = 422,
    ) -> None:
        """Record the refusal, drop what was received, and raise it."""
        text = reason if reason.startswith(f"{code.value}:") else f"{code.value}: {reason}"
        record = PhotoRecord(
            vehicle_id,
            photo_id,
            survey_id,
            REFUSED,
            text[:400],
            time.time(),
            None,
            meta.size_bytes if meta else 0,
            meta.model_dump_json() if meta else None,
        )
        await asyncio.to_thread(self.repository.add, record)
        part, meta_path = self._partial(vehicle_id, photo_id)
        await asyncio.to_thread(discard, part, meta_path)
        self._locks.pop((vehicle_id, photo_id), None)
        log.info("photo %s from %s refused: %s", photo_id, vehicle_id, text)
        raise Refused(code, text, status)

    # -- counting --------------------------------------------------------------------

    def count_unrecorded(self, vehicle_id: str, code: Refusal) -> None:
        self.unrecorded[(vehicle_id, code.value)] += 1

    @staticmethod
    def summary(record: PhotoRecord) -> dict[str, Any]:
        """A stored photo as the survey's photo list shows it."""
        meta = json.loads(record.meta_json) if record.meta_json else {}
        return {
            "photo_id": record.photo_id,
            "vehicle_id": record.vehicle_id,
            "state": record.state,
            "reason": record.reason,
            "size": record.size,
            "received_at": record.received_at,
            "pose": meta.get("pose"),
        }
