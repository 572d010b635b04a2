"""A camera the autopilot fires whose files land in a folder: a camera's SD card mounted
on the companion computer, gphoto2's download folder, a camera SDK's output.

The autopilot tells of each shutter (CAMERA_FEEDBACK; PX4: CAMERA_TRIGGER and
CAMERA_IMAGE_CAPTURED) and the camera writes a file some time later, with a name of its
own choosing that says nothing of the trigger. The two are paired by order and time: the
first new file to the first trigger waiting, provided the file appeared no earlier than
`EARLY_S` before the trigger's message arrived and no later than `PAIR_WINDOW_S` after.
Neither side is ever dropped silently:

- a trigger with no new file within the window makes no photo, and says so (an event,
  the log, `CameraStats.capture_failed`);
- a file that no trigger can claim (it appeared too long before the next trigger, or no
  trigger came for it) is told as unpaired (an event and the log, `FolderCamera.unpaired`)
  and left where it is.

The folder is polled (`POLL_S`), not watched: inotify is not in the standard library,
and a camera's card holds hundreds of files, not millions. Each poll lists the folder
and its subfolders two deep (DCIM/100MSDCF/) up to `MAX_ENTRIES` entries, so a poll's
cost is bounded. A file is taken once its size has stayed the same over two polls (the
camera has finished writing it). Only JPEGs are taken (``.jpg``, ``.jpeg``, any case): a
camera writing RAW beside them has its RAW files ignored. Files already in the folder
when the agent starts are the card's earlier flights and are never taken. The agent
copies each photo into its queue and never deletes from the folder: the card is the
camera's.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import os
import time
from collections import deque
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path

from protocol.photos import MAX_PHOTO_BYTES, CameraIntrinsics
from vehicle_agents.camera.sources import Capture, CaptureError, Shot

log = logging.getLogger(__name__)

FOLDER_SCHEME = "folder:"  # folder:/mnt/sdcard/DCIM
IMAGE_SUFFIXES = frozenset({".jpg", ".jpeg"})
POLL_S = 0.5
PAIR_WINDOW_S = 10.0  # a trigger's file appears within this long of its message
EARLY_S = 2.0  # ... or this much before it (a slow link brings the message late)
MAX_DEPTH = 2  # the folder, and two levels of subfolders below it
MAX_ENTRIES = 20_000  # directory entries looked at per poll
SEVERITY_WARNING = 4

Notify = Callable[[str, int], None]


@dataclass(frozen=True)
class NewFile:
    path: Path
    first_seen: float  # monotonic seconds: the poll that first listed it


class FolderCamera:
    """``folder:PATH``: each trigger's photo is the next new JPEG written under PATH."""

    announces_shots = False

    def __init__(
        self,
        folder: str,
        camera: CameraIntrinsics,
        notify: Notify,
        *,
        monotonic: Callable[[], float] = time.monotonic,
        poll_s: float = POLL_S,
        pair_window_s: float = PAIR_WINDOW_S,
        early_s: float = EARLY_S,
        max_bytes: int = MAX_PHOTO_BYTES,
    ) -> None:
        path = folder.removeprefix(FOLDER_SCHEME)
        if not path:
            raise ValueError("the folder camera needs a folder: folder:/PATH")
        self.folder = Path(path)
        self.camera = camera
        self._notify = notify
        self._monotonic = monotonic
        self.poll_s = poll_s
        self.pair_window_s = pair_window_s
        self.early_s = early_s
        self.max_bytes = max_bytes
        self._known: set[Path] = set()  # taken, told as unpaired, or there before the start
        self._growing: dict[Path, tuple[int, float]] = {}  # size at the last poll, first seen
        self._ready: deque[NewFile] = deque()  # whole files no trigger has claimed yet
        self._baseline_taken = False
        self._changed = asyncio.Event()
        self._warned_truncated = False
        self._warned_missing = False
        self.unpaired = 0

    # -- watching --------------------------------------------------------------------------

    async def run(self) -> None:
        while True:
            # The listing and the sizes off the event loop (a card can be slow); the
            # bookkeeping on it, where the pairing reads it.
            self.update(await asyncio.to_thread(self.snapshot))
            await asyncio.sleep(self.poll_s)

    def poll(self) -> None:
        self.update(self.snapshot())

    def snapshot(self) -> dict[Path, int | None] | None:
        """The JPEGs under the folder and their sizes (None: gone between list and stat);
        None when the folder itself cannot be listed (a card not mounted yet)."""
        if not self.folder.is_dir():
            return None
        return {path: _size(path) for path in self._listing()}

    def update(self, sizes: dict[Path, int | None] | None) -> None:
        """One listing: new whole files become ready, in the order they appeared; ready
        files no trigger can claim any more are told as unpaired."""
        now = self._monotonic()
        if sizes is None:
            if not self._warned_missing:
                self._warned_missing = True
                log.warning("camera folder %s is not there (yet): waiting for it", self.folder)
            return
        present = set(sizes)
        if not self._baseline_taken:
            # Taken when the folder is first there: a card mounted after the agent started
            # brings its earlier flights' files, which are no trigger's either.
            self._known = present  # the card's earlier files: never this flight's photos
            self._baseline_taken = True
            log.info("camera folder %s: %d files there before the start", self.folder, len(present))
            return
        self._known &= present  # a file deleted and written again under its name is new
        fresh: list[NewFile] = []
        for path in sorted(present - self._known):
            size = sizes[path]
            previous = self._growing.get(path)
            if previous is not None and size is not None and size > 0 and size == previous[0]:
                del self._growing[path]
                self._known.add(path)
                fresh.append(NewFile(path, previous[1]))
            elif size is not None:
                self._growing[path] = (size, previous[1] if previous else now)
        for gone in [p for p in self._growing if p not in present]:
            del self._growing[gone]
        self._ready.extend(sorted(fresh, key=lambda f: (f.first_seen, f.path.name)))
        # A trigger arriving from now on claims only files seen after now - early_s; one
        # waiting in the agent's queue has waited at most the pairing window.
        while self._ready and self._ready[0].first_seen < now - self.pair_window_s - self.early_s:
            self._unpaired(self._ready.popleft(), "no camera trigger came for it")
        if fresh:
            self._changed.set()

    def _listing(self) -> Iterator[Path]:
        entries = 0
        stack: list[tuple[Path, int]] = [(self.folder, 0)]
        while stack:
            folder, depth = stack.pop()
            try:
                with os.scandir(folder) as listing:
                    for entry in listing:
                        entries += 1
                        if entries > MAX_ENTRIES:
                            if not self._warned_truncated:
                                self._warned_truncated = True
                                log.warning(
                                    "camera folder %s: more than %d entries; only the first "
                                    "are watched",
                                    self.folder,
                                    MAX_ENTRIES,
                                )
                            return
                        if entry.is_dir(follow_symlinks=False):
                            if depth < MAX_DEPTH:
                                stack.append((Path(entry.path), depth + 1))
                        elif Path(entry.name).suffix.lower() in IMAGE_SUFFIXES:
                            yield Path(entry.path)
            except OSError as error:  # not mounted (yet), or a subfolder removed
                if folder == self.folder:
                    log.debug("camera folder %s unreadable: %s", folder, error)

    def _unpaired(self, new: NewFile, why: str) -> None:
        self.unpaired += 1
        self._notify(
            f"camera file {new.path} not uploaded: {why}; it stays in the folder "
            f"({self.unpaired} unpaired so far)",
            SEVERITY_WARNING,
        )

    # -- pairing ---------------------------------------------------------------------------

    async def capture(self, shot: Shot) -> Capture:
        deadline = shot.arrived + self.pair_window_s
        while True:
            self._changed.clear()
            while self._ready and self._ready[0].first_seen < shot.arrived - self.early_s:
                early = self._ready.popleft()
                self._unpaired(
                    early,
                    f"it appeared {shot.arrived - early.first_seen:.1f} s before the next "
                    f"camera trigger (photo {shot.index})",
                )
            if self._ready:
                new = self._ready.popleft()
                jpeg = await asyncio.to_thread(self._read, new.path)
                log.info("photo %d is %s", shot.index, new.path)
                return Capture(jpeg)
            left = deadline - self._monotonic()
            if left <= 0:
                raise CaptureError(
                    f"no new file in {self.folder} within {self.pair_window_s:g} s of the trigger"
                )
            with contextlib.suppress(TimeoutError):
                await asyncio.wait_for(self._changed.wait(), left)

    def _read(self, path: Path) -> bytes:
        try:
            with path.open("rb") as file:
                data = file.read(self.max_bytes + 1)
        except OSError as error:
            raise CaptureError(f"could not read {path}: {error}") from None
        if len(data) > self.max_bytes:
            raise CaptureError(f"{path} is larger than the {self.max_bytes} bytes a photo may be")
        return data

    def close(self) -> None:
        """Nothing held: the folder is listed afresh at each poll."""


def _size(path: Path) -> int | None:
    try:
        return path.stat().st_size
    except OSError:
        return None
