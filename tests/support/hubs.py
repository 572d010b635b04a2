"""Cheap in-process hubs: the settings every test hub starts from, and one migrated
SQLite database per test process that each hub's data folder starts as a copy of."""

from __future__ import annotations

import atexit
import functools
import os
import shutil
import tempfile
from pathlib import Path

from backend.settings import HubSettings
from backend.storage.database import make_engine, migrate
from gcs.launcher import free_port

ADMIN_PASSWORD = "test-admin-password"
# What every hub the tests start differs in from production, in its environment (the
# fleets' hub processes) and in `hub_settings` (the hubs in the test process):
# - argon2's least cost: the production cost is about 1 s a hash on a busy 2-core
#   machine, paid for each hub's first admin and again for every login;
TEST_HUB_ENV = {"GCS_PASSWORD_HASH_COST": "test"}
# The hub's own name for its SQLite file in the data folder (HubSettings.store_url).
SQLITE_FILE = "gcs.sqlite3"


@functools.cache
def migrated_template() -> Path:
    """An SQLite database migrated to the newest revision, once per test process (each
    pytest-xdist worker has its own); removed when the process ends."""
    folder = Path(tempfile.mkdtemp(prefix="gcs-template-"))
    atexit.register(shutil.rmtree, folder, ignore_errors=True)
    path = folder / SQLITE_FILE
    engine = make_engine(f"sqlite:///{path}")
    migrate(engine)
    engine.dispose()  # checkpoints the WAL into the file: the copy is the whole database
    return path


def seed_database(data_dir: Path) -> None:
    """The migrated template as ``data_dir``'s database, unless it has one already: the
    hub's own migration then finds nothing to do (0.3-0.8 s a hub saved)."""
    target = data_dir / SQLITE_FILE
    if target.exists():
        return
    data_dir.mkdir(mode=0o700, parents=True, exist_ok=True)
    shutil.copyfile(migrated_template(), target)
    os.chmod(target, 0o600)


def hub_settings(data_dir: Path, **overrides: object) -> HubSettings:
    """Settings of an in-process test hub in ``data_dir``; ``overrides`` are the test's
    own. The hub starts on a copy of the migrated template (unless the test names a
    database), with argon2's least cost and without the 3D view (viser's server of its
    own), which the tests that need it turn on (``viz_enabled=True``)."""
    values: dict[str, object] = {
        "port": free_port(),
        "data_dir": data_dir,
        "environment": "development",
        "admin_password": ADMIN_PASSWORD,
        "frontend_dir": data_dir / "no-dashboard",
        "password_hash_cost": "test",
        "viz_enabled": False,
    }
    values.update(overrides)
    if values.get("database_url") is None:
        seed_database(Path(str(values["data_dir"])))
    return HubSettings(**values)  # type: ignore[arg-type]
