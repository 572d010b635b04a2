"""The hub's data folder, its SQLite database (with WAL) and the launcher's logs, and the
agent's outbox and onboard .tlogs, are private to the user who runs them (13.15): folders
0700, files 0600."""

from __future__ import annotations

import os
import stat
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import httpx
import pytest

from gcs.launcher import FleetPlan, LocalFleet, free_port
from tests.support.api import access_token
from tests.support.hubs import TEST_HUB_ENV
from tests.support.mavlink_peer import ScriptedFlightController
from tests.support.processes import agent_process
from tests.support.waiting import poll_until

pytestmark = pytest.mark.integration


@contextmanager
def permissive_umask() -> Iterator[None]:
    """The usual 022: whatever is private must be made so on purpose, not by luck."""
    previous = os.umask(0o022)
    try:
        yield
    finally:
        os.umask(previous)


def _mode(path: Path) -> int:
    return stat.S_IMODE(path.stat().st_mode)


def test_database_wal_and_logs_are_private(tmp_path: Path) -> None:
    data = tmp_path / "data"
    plan = FleetPlan(vehicles=0, port=free_port(), data_dir=data)
    with permissive_umask(), LocalFleet(plan) as fleet:
        fleet.start(TEST_HUB_ENV)
        fleet.wait_until_ready()
        # A write, so that SQLite has its WAL and shared-memory files open.
        access_token(plan.hub_http, "admin", plan.admin_password)
        database = data / "gcs.sqlite3"
        poll_until(
            lambda: Path(f"{database}-wal").exists() and Path(f"{database}-shm").exists(),
            10,
            "the WAL files",
        )
        assert httpx.get(f"{plan.hub_http}/api/v1/health").status_code == 200
        private = {
            data: 0o700,
            fleet.log_dir: 0o700,
            fleet.log_dir / "hub.log": 0o600,
            database: 0o600,
            Path(f"{database}-wal"): 0o600,
            Path(f"{database}-shm"): 0o600,
        }
        found = {path: _mode(path) for path in private}
    assert {str(p): oct(m) for p, m in found.items()} == {
        str(p): oct(m) for p, m in private.items()
    }


def test_an_existing_world_readable_database_is_made_private(tmp_path: Path) -> None:
    """A database created before the rule (0644, in a 0755 folder) is tightened at start."""
    from backend.storage.database import make_engine

    folder = tmp_path / "old"
    folder.mkdir(mode=0o755)
    database = folder / "gcs.sqlite3"
    database.touch(mode=0o644)
    os.chmod(database, 0o644)
    make_engine(f"sqlite:///{database}").dispose()
    assert oct(_mode(database)) == oct(0o600)


def test_the_agents_outbox_and_onboard_tlogs_are_private(tmp_path: Path) -> None:
    """On the vehicle too: the outbox (an outage's telemetry, in SQLite with its WAL) and
    the onboard .tlogs are the agent's user's only, whatever the umask it started with."""
    state = tmp_path / "state"
    outbox, tlogs = state / "outbox", state / "tlogs"
    with (
        permissive_umask(),
        ScriptedFlightController(armed=True) as fcu,  # armed: the .tlog is being written
        agent_process(
            f"http://127.0.0.1:{free_port()}",  # no hub: the outbox keeps it all
            "t" * 32,
            "private_1",
            fcu.port,
            tmp_path,
            extra_args=["--outbox-dir", str(outbox), "--tlog-dir", str(tlogs)],
        ),
    ):
        database = outbox / "private_1.outbox.sqlite"
        written = poll_until(
            lambda: Path(f"{database}-wal").exists() and list(tlogs.glob("*.tlog")),
            30,
            "the outbox's WAL and a .tlog",
        )
        private = {
            outbox: 0o700,
            tlogs: 0o700,
            database: 0o600,
            Path(f"{database}-wal"): 0o600,
            written[0]: 0o600,
        }
        found = {path: _mode(path) for path in private}
    assert {str(p): oct(m) for p, m in found.items()} == {
        str(p): oct(m) for p, m in private.items()
    }
