"""Uploaded onboard .tlogs are deleted by age and by a size budget; no other file is."""

from __future__ import annotations

import os
from pathlib import Path

from vehicle_agents.tlog.pruning import DAY_S, UPLOADED_DIR, TlogRetention, prune_uploaded_tlogs

NOW = 1_800_000_000.0


def _tlog(path: Path, size: int, age_days: float) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_bytes(b"\xfd" * size)
    mtime = NOW - age_days * DAY_S
    os.utime(path, (mtime, mtime))
    return path


def _uploaded(directory: Path, name: str, size: int, age_days: float) -> Path:
    return _tlog(directory / UPLOADED_DIR / f"{name}.tlog", size, age_days)


def test_uploaded_files_past_the_age_limit_go_and_pending_ones_stay(tmp_path: Path) -> None:
    old = _uploaded(tmp_path, "old", 100, age_days=10)
    week = _uploaded(tmp_path, "week", 100, age_days=7.5)
    recent = _uploaded(tmp_path, "recent", 100, age_days=1)
    pending = _tlog(tmp_path / "pending.tlog", 100, age_days=30)  # the hub never took it

    deleted = prune_uploaded_tlogs(tmp_path, TlogRetention(keep_days=7), NOW)

    assert deleted == [old, week]
    assert recent.exists()
    assert pending.exists()


def test_the_oldest_uploaded_go_until_everything_onboard_fits_the_budget(
    tmp_path: Path,
) -> None:
    first = _uploaded(tmp_path, "a", 100, age_days=3)
    second = _uploaded(tmp_path, "b", 100, age_days=2)
    third = _uploaded(tmp_path, "c", 100, age_days=1)
    pending = _tlog(tmp_path / "pending.tlog", 150, age_days=0.5)  # counts, but stays

    deleted = prune_uploaded_tlogs(tmp_path, TlogRetention(keep_bytes=300), NOW)

    assert deleted == [first, second]  # 450 bytes -> 250
    assert third.exists()
    assert pending.exists()


def test_files_not_yet_uploaded_and_the_one_being_written_are_never_deleted(
    tmp_path: Path,
) -> None:
    uploaded = _uploaded(tmp_path, "done", 100, age_days=1)
    pending = _tlog(tmp_path / "pending.tlog", 5000, age_days=90)
    recording = _tlog(tmp_path / "now.tlog", 5000, age_days=0)

    retention = TlogRetention(keep_days=0, keep_bytes=0)
    deleted = prune_uploaded_tlogs(tmp_path, retention, NOW, recording=recording)

    assert deleted == [uploaded]
    assert pending.exists()
    assert recording.exists()


def test_within_both_limits_nothing_goes(tmp_path: Path) -> None:
    kept = [_uploaded(tmp_path, f"f{n}", 100, age_days=n) for n in range(1, 6)]
    assert prune_uploaded_tlogs(tmp_path, TlogRetention(), NOW) == []
    assert all(path.exists() for path in kept)


def test_no_folder_yet_is_nothing_to_do(tmp_path: Path) -> None:
    assert prune_uploaded_tlogs(tmp_path / "absent", TlogRetention(), NOW) == []
