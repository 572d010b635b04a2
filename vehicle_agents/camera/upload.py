"""The queued photos to the hub over HTTP, resumable, and never at telemetry's expense.

Per photo (the hub's side is backend/imagery/photos/routes.py):

1. ``GET /api/v1/vehicles/{vehicle_id}/photos/{photo_id}``: how many bytes the hub has
   committed (404: none). A cut upload resumes there, not from the start.
2. ``PUT .../photos/{photo_id}?offset=N`` with the next chunk as the body; the first
   chunk (offset 0) carries the photo's PhotoMeta as JSON in ``X-Photo-Meta``. The hub
   answers the new committed offset; 409 with its own offset if ours was wrong (resume
   from there); 201 once the last chunk is in and the photo passed its checks. A photo
   id the hub already stored answers 200 ``stored`` at once: the upload is idempotent.
3. The hub's refusal of the photo itself (413 or 422 with a ``code``: a pose far from the
   survey, a corrupt image...) is for good: the photo is removed from the queue and the
   operator gets an event with the hub's reason. A 413 without one is a body limit on the
   way (the hub's GCS_MAX_BODY_BYTES, a proxy's): the chunks are halved. Everything else
   (no route to the hub, 5xx, 401/403 while a token is being fixed) is retried with
   full-jitter backoff (common/retry.py), the photo kept.

Bandwidth: chunks are small (256 KiB) and paced by a token bucket (``rate_bytes_per_s``),
with at most ``concurrency`` photos in flight, so the WebSocket's telemetry always finds
room on a narrow link; each chunk is a request of its own, so no upload holds the link
for longer than one chunk takes.
"""

from __future__ import annotations

import asyncio
import json
import logging
import time
import urllib.parse
from collections.abc import Callable
from dataclasses import dataclass

from common.retry import Backoff, Retries
from vehicle_agents.camera.queue import PhotoQueue, QueuedPhoto
from vehicle_agents.hub.http import HttpError, send

log = logging.getLogger(__name__)

CHUNK_BYTES = 256 * 1024
REQUEST_TIMEOUT_S = 30.0
UPLOAD_BACKOFF = Backoff(initial_s=1.0, max_s=15.0)
IDLE_POLL_S = 1.0  # how often an idle uploader looks for new photos (put() also wakes it)
MIN_CHUNK_BYTES = 16 * 1024
# The refusals that are not for good: the vehicle's share of the hub's disk (an admin
# may free it), and its uploads at once (a stale one expires).
RETRIED_REFUSALS = frozenset({"quota", "uploads_in_progress"})
MAX_OFFSET_CORRECTIONS = 3  # 409s in a row for one photo before it is tried again later
EVENT_TEXT_ROOM = 400

Notify = Callable[[str, int], None]
SEVERITY_WARNING, SEVERITY_INFO = 4, 6


class TokenBucket:
    """At most ``rate`` bytes a second on average, in bursts of up to ``burst`` bytes."""

    def __init__(
        self, rate: float, burst: float, monotonic: Callable[[], float] = time.monotonic
    ) -> None:
        self.rate = rate
        self.burst = burst
        self._monotonic = monotonic
        self._tokens = burst
        self._at = monotonic()
        self._lock = asyncio.Lock()

    async def take(self, amount: int) -> None:
        async with self._lock:  # one waiter at a time: first come, first served
            now = self._monotonic()
            self._tokens = min(self.burst, self._tokens + (now - self._at) * self.rate)
            self._at = now
            self._tokens -= amount
            if self._tokens < 0:
                await asyncio.sleep(-self._tokens / self.rate)


@dataclass
class UploadStats:
    uploaded: int = 0
    refused: int = 0
    resumed: int = 0  # uploads that went on from a committed offset above 0
    chunks: int = 0
    bytes_sent: int = 0
    failures: int = 0  # attempts that will be retried


class Refused(Exception):
    """The hub refused the photo for good; the message is its reason."""


class PhotoUploader:
    def __init__(
        self,
        queue: PhotoQueue,
        base_url: str,
        vehicle_id: str,
        token: str,
        notify: Notify | None = None,
        *,
        rate_bytes_per_s: float = 2 * 1024 * 1024,
        concurrency: int = 1,
        chunk_bytes: int = CHUNK_BYTES,
        backoff: Backoff = UPLOAD_BACKOFF,
    ) -> None:
        self.queue = queue
        self.url = f"{base_url}/api/v1/vehicles/{urllib.parse.quote(vehicle_id, safe='')}/photos"
        self._token = token
        self._notify = notify or (lambda text, severity: None)
        self.chunk_bytes = chunk_bytes
        self.concurrency = concurrency
        # Bursts of one chunk at most: a narrow link never gets seconds of photo at once.
        self.bucket = TokenBucket(rate_bytes_per_s, chunk_bytes)
        self.backoff = backoff
        self.stats = UploadStats()
        self._in_flight: set[str] = set()
        self._failing = False

    async def run(self) -> None:
        async with asyncio.TaskGroup() as tasks:
            for _ in range(self.concurrency):
                tasks.create_task(self._worker())

    async def _worker(self) -> None:
        retries = Retries(self.backoff)
        while True:
            photo = self.queue.oldest(skip=self._in_flight)
            if photo is None:
                self.queue.changed.clear()
                if self.queue.oldest(skip=self._in_flight) is None:
                    await asyncio.to_thread(self.queue.changed.wait, IDLE_POLL_S)
                continue
            self._in_flight.add(photo.photo_id)
            try:
                await self.upload(photo)
            except Refused as refusal:
                self.stats.refused += 1
                self.queue.remove(photo.photo_id, uploaded=False)
                text = f"photo {photo.photo_id} refused by the hub: {refusal}"
                log.warning(text)
                self._notify(text[:EVENT_TEXT_ROOM], SEVERITY_WARNING)
            except (OSError, HttpError, ValueError) as error:
                self.stats.failures += 1
                wait = retries.next_delay()
                log.info(
                    "photo %s upload failed (%s); retrying in %.1f s", photo.photo_id, error, wait
                )
                self._failing = True
                self._in_flight.discard(photo.photo_id)
                await retries.sleep(wait)
                continue
            else:
                retries.reset()
                self.queue.remove(photo.photo_id, uploaded=True)
                self.stats.uploaded += 1
                if self._failing:
                    self._failing = False
                    log.info("photo uploads going again; %d waiting", len(self.queue))
            self._in_flight.discard(photo.photo_id)

    async def upload(self, photo: QueuedPhoto) -> None:
        """Send the photo from where the hub has it up to its end; returns once stored."""
        url = f"{self.url}/{urllib.parse.quote(photo.photo_id, safe='')}"
        data = await asyncio.to_thread(photo.path.read_bytes)
        offset = await self._committed(url)
        if offset is None:
            return  # the hub has it already
        if offset:
            self.stats.resumed += 1
        corrections = 0
        while True:
            chunk = data[offset : offset + self.chunk_bytes]
            await self.bucket.take(len(chunk))
            headers = {"Content-Type": "application/octet-stream"}
            if offset == 0:
                headers["X-Photo-Meta"] = photo.meta.model_dump_json()
            try:
                answer = await asyncio.to_thread(
                    send,
                    "PUT",
                    f"{url}?offset={offset}",
                    token=self._token,
                    body=chunk,
                    headers=headers,
                    timeout_s=REQUEST_TIMEOUT_S,
                )
            except HttpError as error:
                if error.status == 409 and corrections < MAX_OFFSET_CORRECTIONS:
                    corrections += 1  # the hub has another offset: go on from its
                    offset = _received(error.body)
                    continue
                code = _code(error.body)
                if code in RETRIED_REFUSALS:
                    raise
                if code is not None:  # the hub refused the photo itself, with its reason
                    raise Refused(_detail(error.body)) from None
                if error.status == 413 and self.chunk_bytes > MIN_CHUNK_BYTES:
                    # A hub (or a proxy) that takes smaller bodies than our chunks.
                    self.chunk_bytes //= 2
                    log.warning("photo chunks refused as too large; now %d bytes", self.chunk_bytes)
                    continue
                raise
            corrections = 0
            self.stats.chunks += 1
            self.stats.bytes_sent += len(chunk)
            status = json.loads(answer.body)
            if status.get("state") == "stored":
                return
            offset = int(status["received"])

    async def _committed(self, url: str) -> int | None:
        """The bytes the hub has of this photo, or None if it stored it already."""
        try:
            answer = await asyncio.to_thread(
                send, "GET", url, token=self._token, timeout_s=REQUEST_TIMEOUT_S
            )
        except HttpError as error:
            if error.status == 404:
                return 0
            raise
        status = json.loads(answer.body)
        if status.get("state") == "stored":
            return None
        if status.get("state") == "refused":
            raise Refused(str(status.get("reason")))
        return int(status["received"])


def _received(body: str) -> int:
    try:
        return int(json.loads(body)["received"])
    except (ValueError, KeyError, TypeError):
        return 0


def _code(body: str) -> str | None:
    """The refusal's code (no_pose, corrupt_image...) when the answer is the hub's verdict
    on the photo, not a limit or a fault on the way (a proxy's 413, a 5xx)."""
    try:
        code = json.loads(body).get("code")
    except (ValueError, AttributeError):
        return None
    return code if isinstance(code, str) else None


def _detail(body: str) -> str:
    """The hub's reason, from its JSON error body (FastAPI's ``detail``)."""
    try:
        detail = json.loads(body)["detail"]
    except (ValueError, KeyError, TypeError):
        return body
    if isinstance(detail, list) and detail and isinstance(detail[0], dict):
        return str(detail[0].get("msg", detail))
    return str(detail)
