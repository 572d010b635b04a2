"""After landing, hand each finished onboard .tlog to the hub, retrying until it takes it."""

from __future__ import annotations

import asyncio
import logging
from pathlib import Path

from vehicle_agents.fcu_link import MavMessage
from vehicle_agents.tlog import TlogRecorder, TlogUploadError, upload_tlog

log = logging.getLogger(__name__)

RETRY_S = 30.0


class TlogUploader:
    def __init__(self, recorder: TlogRecorder, url: str, token: str) -> None:
        self.recorder = recorder
        self.url = url
        self._token = token
        self._landed = asyncio.Event()

    def on_message(self, message: MavMessage) -> None:
        """A finished file appears when the vehicle disarms; wake the uploader then."""
        if message.get_type() == "HEARTBEAT" and self.recorder.finished:
            self._landed.set()

    async def run(self) -> None:
        while True:
            await self._landed.wait()
            self._landed.clear()
            while self.recorder.finished:
                path = self.recorder.finished[0]
                try:
                    await asyncio.to_thread(upload_tlog, path, self.url, self._token)
                except TlogUploadError as refusal:
                    if refusal.status >= 500 or refusal.status == 429:
                        log.warning(
                            "hub could not take %s (%s); retrying", path.name, refusal.status
                        )
                        await asyncio.sleep(RETRY_S)
                        continue
                    # Refused for good (too large, token revoked): it stays on board.
                    log.error("hub refused tlog %s: %s; kept on board", path.name, refusal)
                    self.recorder.finished.popleft()
                    continue
                except OSError as error:
                    log.warning("tlog upload of %s failed; retrying: %s", path.name, error)
                    await asyncio.sleep(RETRY_S)
                    continue
                self.recorder.finished.popleft()
                try:
                    _mark_uploaded(path)
                except OSError as error:
                    log.warning("uploaded %s but could not move it aside: %s", path.name, error)
                log.info("uploaded onboard tlog %s", path.name)


def _mark_uploaded(path: Path) -> None:
    """Keep the file (the onboard copy is the last resort) but out of the upload queue."""
    done = path.parent / "uploaded"
    done.mkdir(exist_ok=True)
    path.rename(done / path.name)
