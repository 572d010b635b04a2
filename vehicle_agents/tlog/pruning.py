"""Deleting onboard .tlogs the hub already has, so an SD card never fills with them.

An uploaded file moves to ``<tlog dir>/uploaded/`` once the hub has answered 2xx (the hub
then holds it, checked to be MAVLink). Only those are ever deleted: first the ones older
than the age limit, then the oldest of the rest while all onboard .tlogs together (the ones
not yet uploaded and the flight being written included) are over the size budget. A file
not yet uploaded is never deleted, even when it alone is over the budget.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass
from pathlib import Path

log = logging.getLogger(__name__)

UPLOADED_DIR = "uploaded"
DAY_S = 86_400.0
MIB = 1024 * 1024


@dataclass(frozen=True)
class TlogRetention:
    """How long, and within how much room, uploaded onboard logs are kept."""

    keep_days: float = 7.0
    keep_bytes: int = 2048 * MIB


@dataclass(frozen=True)
class _Tlog:
    path: Path
    size: int
    mtime: float


def _tlogs(directory: Path) -> list[_Tlog]:
    """The .tlogs in ``directory``, oldest first; one that vanishes meanwhile is skipped."""
    found = []
    for path in directory.glob("*.tlog"):
        try:
            stat = path.stat()
        except OSError:
            continue
        found.append(_Tlog(path, stat.st_size, stat.st_mtime))
    return sorted(found, key=lambda tlog: (tlog.mtime, tlog.path.name))


def prune_uploaded_tlogs(
    directory: Path, retention: TlogRetention, now: float, recording: Path | None = None
) -> list[Path]:
    """Delete uploaded .tlogs under ``directory`` as ``retention`` says; the ones deleted.

    ``now`` is the unix time that ages are measured against (a file's age is since its
    last write, the end of its flight); ``recording``, the file being written, is never
    deleted even should it be in the uploaded folder."""
    uploaded = [tlog for tlog in _tlogs(directory / UPLOADED_DIR) if tlog.path != recording]
    # Not uploaded yet, or being written: they count against the budget, and are kept.
    total = sum(tlog.size for tlog in _tlogs(directory)) + sum(tlog.size for tlog in uploaded)
    oldest_kept = now - retention.keep_days * DAY_S
    deleted = []
    for tlog in uploaded:
        too_old = tlog.mtime < oldest_kept
        if not too_old and total <= retention.keep_bytes:
            break  # the rest are newer: neither too old nor needed to meet the budget
        try:
            tlog.path.unlink()
        except FileNotFoundError:
            pass
        except OSError as error:
            log.warning("could not delete uploaded onboard tlog %s: %s", tlog.path.name, error)
            continue
        total -= tlog.size
        deleted.append(tlog.path)
        reason = "older than the age limit" if too_old else "over the size budget"
        log.info("deleted uploaded onboard tlog %s (%s)", tlog.path.name, reason)
    return deleted
