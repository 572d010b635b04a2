"""Uploads in progress, on disk: what each one holds and reserves, and which have gone stale.

An upload in progress is ``<photos>/.partial/<vehicle>/<photo>.part`` (the bytes so far)
beside ``<photo>.json`` (its PhotoMeta, with the size it declared). Unbounded, one agent
token wrote 2.5 GB of such files in 20 s, outside the vehicle's quota, and nothing ever
removed an abandoned one. So an upload reserves its declared size in the quota from its
first chunk, a vehicle has at most so many at once, and one left untouched for long
enough is removed.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path

from pydantic import ValidationError

from protocol.photos import PhotoMeta


@dataclass(frozen=True)
class PartialLimits:
    max_per_vehicle: int = 8  # the agent uploads at most 8 photos at once
    expiry_s: float = 6 * 3600.0  # an upload untouched this long is given up


@dataclass(frozen=True)
class InProgress:
    photo_id: str
    reserved_bytes: int  # what it declared, or what it holds if that is more
    touched: float  # when a chunk last arrived (the files' newest mtime)


def in_progress(folder: Path) -> list[InProgress]:
    """The uploads in progress in one vehicle's folder (blocking: call it in a thread).
    A ``.part`` whose metadata is missing or unreadable (a hub stopped between the two
    writes) counts too, reserving what it holds."""
    uploads = []
    for name in {path.stem for path in folder.glob("*.part")} | {
        path.stem for path in folder.glob("*.json")
    }:
        meta_path, part = folder / f"{name}.json", folder / f"{name}.part"
        try:
            declared = PhotoMeta.model_validate_json(meta_path.read_bytes()).size_bytes
        except (OSError, ValidationError):
            declared = 0
        held, touched = _size_and_mtime(part)
        _, meta_touched = _size_and_mtime(meta_path)
        uploads.append(InProgress(name, max(declared, held), max(touched, meta_touched)))
    return uploads


def stale(root: Path, expiry_s: float, now: float | None = None) -> list[tuple[str, str]]:
    """(vehicle, photo) of every upload under ``root`` untouched for ``expiry_s``."""
    cutoff = (time.time() if now is None else now) - expiry_s
    found = []
    for folder in root.iterdir() if root.is_dir() else ():
        if folder.is_dir():
            found += [(folder.name, u.photo_id) for u in in_progress(folder) if u.touched < cutoff]
    return found


def _size_and_mtime(path: Path) -> tuple[int, float]:
    try:
        status = path.stat()
    except FileNotFoundError:
        return 0, 0.0
    return status.st_size, status.st_mtime
