"""One upload's files on disk and what the hub answers about it.

An upload in progress is ``<photos>/.partial/<vehicle>/<photo>.part`` (the bytes so far)
beside ``<photo>.json`` (its metadata); a stored photo is ``<photos>/<vehicle>/<photo>.jpg``.
The ids name files, so each is checked to be a plain name first.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

PARTIAL_DIR = ".partial"
STORED, REFUSED = "stored", "refused"


@dataclass(frozen=True)
class UploadState:
    """What the hub has of one photo: ``received`` bytes of ``size``; ``state`` is
    "receiving", "stored" or "refused" (with the reason)."""

    received: int
    size: int | None
    state: str
    reason: str | None = None

    def body(self) -> dict[str, Any]:
        return {k: v for k, v in self.__dict__.items() if v is not None}


class OffsetMismatch(Exception):
    def __init__(self, received: int) -> None:
        super().__init__(f"the upload goes on at byte {received}")
        self.received = received


def safe_name(identifier: str) -> str:
    """An id as a file or folder name: the protocol's patterns allow only
    [A-Za-z0-9_.-], which leaves the dot names to refuse."""
    if identifier in ("", ".", "..") or "/" in identifier or "\\" in identifier:
        raise ValueError(f"{identifier!r} cannot name a file")
    return identifier


def partial_paths(root: Path, vehicle_id: str, photo_id: str) -> tuple[Path, Path]:
    """An upload in progress: its ``.part`` bytes and its ``.json`` metadata."""
    folder = root / PARTIAL_DIR / safe_name(vehicle_id)
    name = safe_name(photo_id)
    return folder / f"{name}.part", folder / f"{name}.json"


def final_path(root: Path, vehicle_id: str, photo_id: str) -> Path:
    """Where a stored photo lives."""
    return root / safe_name(vehicle_id) / f"{safe_name(photo_id)}.jpg"


def size_of(path: Path) -> int:
    try:
        return path.stat().st_size
    except FileNotFoundError:
        return 0


def append(path: Path, chunk: bytes) -> None:
    with path.open("ab") as file:
        file.write(chunk)


def discard(*paths: Path) -> None:
    for path in paths:
        path.unlink(missing_ok=True)
