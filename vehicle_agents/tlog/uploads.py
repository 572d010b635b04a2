"""After landing, hand each finished onboard .tlog to the hub, retrying until it takes it.

A failed upload never ends the uploader and never drops the file: the operator gets an
event saying what went wrong, and the file is tried again with exponential backoff (with
full jitter, so a fleet that lands together does not retry in step). Uploaded files are
kept on board, within the age and size limits of a `TlogRetention`."""

from __future__ import annotations

import asyncio
import logging
import time
from collections.abc import Callable
from pathlib import Path

from common.retry import Backoff, Retries
from vehicle_agents.fcu.messages import MavMessage
from vehicle_agents.tlog.pruning import UPLOADED_DIR, TlogRetention, prune_uploaded_tlogs
from vehicle_agents.tlog.recorder import TlogRecorder, TlogUploadError, upload_tlog

log = logging.getLogger(__name__)

# MAV_SEVERITY of the events the uploader raises.
SEVERITY_WARNING, SEVERITY_INFO = 4, 6
EVENT_TEXT_ROOM = 400

Notify = Callable[[str, int], None]
"""Raise an event for the operator: its text and MAV_SEVERITY."""


# Waits between failed uploads: up to 5 s after the first, doubling to 10 min.
UPLOAD_BACKOFF = Backoff(initial_s=5.0, max_s=600.0)
# Uploaded files also age out while the vehicle sits on the ground for days.
PRUNE_EVERY_S = 3600.0


class TlogUploader:
    def __init__(
        self,
        recorder: TlogRecorder,
        url: str,
        token: str,
        notify: Notify | None = None,
        backoff: Backoff = UPLOAD_BACKOFF,
        retention: TlogRetention | None = None,
        clock: Callable[[], float] = time.time,
    ) -> None:
        self.recorder = recorder
        self.url = url
        self._token = token
        self._notify = notify or (lambda text, severity: None)
        self.backoff = backoff
        self.retention = retention or TlogRetention()
        self._clock = clock
        self._landed = asyncio.Event()
        # The last problem told to the operator, per file: a repeat is logged, not raised.
        self._reported: dict[Path, str] = {}

    def on_message(self, message: MavMessage) -> None:
        """A finished file appears when the vehicle disarms; wake the uploader then."""
        if message.get_type() == "HEARTBEAT" and self.recorder.finished:
            self._landed.set()

    async def run(self) -> None:
        retries = Retries(self.backoff)
        while True:
            await self.prune()  # at start, then hourly and after each upload
            try:
                async with asyncio.timeout(PRUNE_EVERY_S):
                    await self._landed.wait()
            except TimeoutError:
                continue
            self._landed.clear()
            while self.recorder.finished:
                path = self.recorder.finished[0]
                problem = await self._upload(path)
                if problem is None:
                    retries.reset()
                    await self.prune()
                    continue
                # Kept, at the back of the queue: a file the hub refuses does not hold up
                # the flights after it.
                self.recorder.finished.rotate(-1)
                wait = retries.next_delay()
                self._report(path, problem, wait)
                await retries.sleep(wait)

    async def _upload(self, path: Path) -> str | None:
        """None once the hub has the file, else what went wrong."""
        try:
            await asyncio.to_thread(upload_tlog, path, self.url, self._token)
        except TlogUploadError as refusal:
            return str(refusal)
        except (OSError, ValueError) as error:
            return f"uploading {path.name} failed: {error}"
        self.recorder.finished.remove(path)
        if self._reported.pop(path, None) is not None:
            self._notify(f"onboard log {path.name} uploaded after earlier failures", SEVERITY_INFO)
        try:
            _mark_uploaded(path)
        except OSError as error:
            log.warning("uploaded %s but could not move it aside: %s", path.name, error)
        log.info("uploaded onboard tlog %s", path.name)
        return None

    async def prune(self) -> list[Path]:
        """Delete the uploaded files the retention no longer keeps; the ones deleted."""
        return await asyncio.to_thread(
            prune_uploaded_tlogs,
            self.recorder.directory,
            self.retention,
            self._clock(),
            self.recorder.recording,
        )

    def _report(self, path: Path, problem: str, wait: float) -> None:
        log.warning("%s; kept on board, retrying in %.0f s", problem, wait)
        if self._reported.get(path) != problem:
            self._reported[path] = problem
            # An event's text is bounded; the hub's answer in ``problem`` is not.
            self._notify(f"{problem[:EVENT_TEXT_ROOM]}; kept on board, retrying", SEVERITY_WARNING)


def _mark_uploaded(path: Path) -> None:
    """Keep the file (the onboard copy is the last resort) but out of the upload queue."""
    done = path.parent / UPLOADED_DIR
    done.mkdir(exist_ok=True)
    path.rename(done / path.name)
