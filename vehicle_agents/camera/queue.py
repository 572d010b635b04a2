"""The photos waiting for the hub, on the onboard computer's disk, within a byte budget.

Each photo is two files in the queue's folder: ``<photo id>.jpg`` (the geotagged JPEG)
and ``<photo id>.json`` (its PhotoMeta), both written to a temporary name and renamed,
so a power cut leaves a photo whole or absent. The JSON is written last: a JPEG without
its JSON is an unfinished write and is removed at start. Photos survive an agent restart
and are uploaded oldest first. When a new photo takes the queue over its budget, the
oldest are deleted (never the one being added) and counted, with an event: the link was
down longer than the disk could hold.
"""

from __future__ import annotations

import contextlib
import logging
import os
import threading
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from pydantic import ValidationError

from protocol.photos import PhotoMeta

log = logging.getLogger(__name__)

Notify = Callable[[str, int], None]
SEVERITY_WARNING = 4
MIB = 1024 * 1024


@dataclass(frozen=True)
class QueuedPhoto:
    meta: PhotoMeta
    path: Path  # the JPEG

    @property
    def photo_id(self) -> str:
        return self.meta.photo_id


class PhotoQueue:
    """Oldest first; thread-safe (the trigger writes from a worker thread, the uploader
    reads from the event loop)."""

    def __init__(self, directory: Path, budget_bytes: int, notify: Notify | None = None) -> None:
        self.directory = directory
        self.budget_bytes = budget_bytes
        self._notify = notify or (lambda text, severity: None)
        self._lock = threading.Lock()
        self._photos: dict[str, QueuedPhoto] = {}  # insertion order: oldest first
        self._bytes = 0
        self.dropped = 0
        self.uploaded = 0
        self.changed = threading.Event()  # set on every put, for a waiting uploader
        directory.mkdir(parents=True, exist_ok=True)
        self._load()

    def _load(self) -> None:
        found = []
        for meta_path in self.directory.glob("*.json"):
            jpeg = meta_path.with_suffix(".jpg")
            try:
                meta = PhotoMeta.model_validate_json(meta_path.read_bytes())
                found.append((meta_path.stat().st_mtime_ns, QueuedPhoto(meta, jpeg)))
            except (OSError, ValidationError) as error:
                log.warning("queued photo %s unreadable, removed: %s", meta_path.name, error)
                _remove(meta_path, jpeg)
        for _, photo in sorted(found, key=lambda item: item[0]):
            if photo.path.is_file():
                self._photos[photo.photo_id] = photo
                self._bytes += photo.path.stat().st_size
            else:
                _remove(photo.path.with_suffix(".json"))
        known = {photo.path for photo in self._photos.values()}
        for stray in [*self.directory.glob("*.jpg"), *self.directory.glob("*.tmp")]:
            if stray not in known:  # a write cut short
                _remove(stray)
        if self._photos:
            log.info("%d photos from an earlier run wait for the hub", len(self._photos))

    def __len__(self) -> int:
        with self._lock:
            return len(self._photos)

    @property
    def size_bytes(self) -> int:
        with self._lock:
            return self._bytes

    def put(self, meta: PhotoMeta, jpeg: bytes) -> None:
        """Keep a photo (blocking file I/O: from a worker thread)."""
        base = self.directory / meta.photo_id
        _write_atomically(base.with_suffix(".jpg"), jpeg)
        _write_atomically(base.with_suffix(".json"), meta.model_dump_json().encode())
        dropped: list[QueuedPhoto] = []
        with self._lock:
            old = self._photos.pop(meta.photo_id, None)
            if old is not None:  # the same photo again (a restart re-took it): replaced
                self._bytes -= old.meta.size_bytes
            self._photos[meta.photo_id] = QueuedPhoto(meta, base.with_suffix(".jpg"))
            self._bytes += len(jpeg)
            while self._bytes > self.budget_bytes and len(self._photos) > 1:
                oldest = next(iter(self._photos.values()))
                del self._photos[oldest.photo_id]
                self._bytes -= oldest.meta.size_bytes
                self.dropped += 1
                dropped.append(oldest)
        for photo in dropped:
            _remove(photo.path, photo.path.with_suffix(".json"))
            text = (
                f"photo {photo.photo_id} deleted unsent: the onboard photo queue is over its "
                f"budget of {self.budget_bytes / MIB:.0f} MiB ({self.dropped} deleted so far)"
            )
            log.warning(text)
            self._notify(text, SEVERITY_WARNING)
        self.changed.set()

    def oldest(self, skip: set[str] = frozenset()) -> QueuedPhoto | None:  # type: ignore[assignment]
        """The oldest photo not in ``skip`` (those being uploaded), or None."""
        with self._lock:
            return next((p for p in self._photos.values() if p.photo_id not in skip), None)

    def contains(self, photo_id: str) -> bool:
        with self._lock:
            return photo_id in self._photos

    def remove(self, photo_id: str, *, uploaded: bool) -> None:
        """The hub has the photo (or refused it for good): off the disk."""
        with self._lock:
            photo = self._photos.pop(photo_id, None)
            if photo is None:
                return
            self._bytes -= photo.meta.size_bytes
            if uploaded:
                self.uploaded += 1
        _remove(photo.path, photo.path.with_suffix(".json"))


def _write_atomically(path: Path, data: bytes) -> None:
    temporary = path.with_suffix(path.suffix + ".tmp")
    with temporary.open("wb") as file:
        file.write(data)
        file.flush()
        os.fsync(file.fileno())
    temporary.replace(path)


def _remove(*paths: Path) -> None:
    for path in paths:
        with contextlib.suppress(FileNotFoundError):
            path.unlink()
