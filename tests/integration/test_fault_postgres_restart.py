"""PostgreSQL restarted under load: a private cluster (initdb in a temporary folder, run as
the postgres user on a free port; the machine's shared server is never touched) is
stopped with ``-m immediate`` (a crash: no checkpoint, open connections cut) while an
agent streams telemetry, and started again; then restarted ``-m fast`` under the same
load.

Guaranteed: the live service and the safety commands go on through the outage, /health
says the database is away while it is, and every sample the hub accepted is stored once
it is back, each once; so are the audit and command-log rows of the commands.
"""

from __future__ import annotations

import glob
import os
import pwd
import shutil
import subprocess
import tempfile
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import pytest

from gcs.launcher import free_port
from tests.conftest import ADMIN_PASSWORD, hub_settings
from tests.support.agents import scripted_agent, telemetry_frame
from tests.support.api import access_token, api_client
from tests.support.databases import answering
from tests.support.hub_server import running_hub
from tests.support.store_outage import (
    degraded,
    everything_stored,
    safety_commands_go_through,
    stored,
    streaming,
)
from tests.support.waiting import poll_until

pytestmark = pytest.mark.integration

RATE_HZ = 100  # a fleet's worth of samples from one agent


def _pg_bin(name: str) -> str:
    found = sorted(glob.glob(f"/usr/lib/postgresql/*/bin/{name}")) or [
        path for path in (shutil.which(name),) if path
    ]
    if not found:
        pytest.skip(f"no PostgreSQL server binaries ({name}) on this machine")
    return found[-1]


def _as_postgres(tool: str, *args: str, check: bool = True) -> None:
    """A server program run as the postgres user (the server refuses to run as root)."""
    runuser = ["runuser", "-u", "postgres", "--"]
    subprocess.run([*runuser, _pg_bin(tool), *args], check=check, capture_output=True, timeout=120)


class PrivateCluster:
    def __init__(self, directory: Path, port: int) -> None:
        self.directory, self.port = directory, port
        self.url = f"postgresql+psycopg://postgres@127.0.0.1:{port}/postgres"

    def ctl(self, *args: str) -> None:
        log = str(self.directory / "server.log")
        _as_postgres("pg_ctl", "-D", str(self.directory), "-w", "-t", "60", "-l", log, *args)


@contextmanager
def private_cluster() -> Iterator[PrivateCluster]:
    """A PostgreSQL cluster of this test's own; stopped and deleted after. Needs root
    (to run the server as the postgres user); skipped without, except in CI."""
    try:
        pwd.getpwnam("postgres")
        usable = os.geteuid() == 0
    except KeyError:
        usable = False
    if not usable and os.environ.get("CI", "").lower() != "true":
        pytest.skip("a private PostgreSQL cluster needs root and a postgres user")
    # Not under pytest's tmp_path: its parents are closed to the postgres user.
    root = Path(tempfile.mkdtemp(prefix="gcs-pg-"))
    data = root / "data"
    try:
        shutil.chown(root, "postgres")
        initdb_options = ("-A", "trust", "-U", "postgres", "--no-sync", "-E", "UTF8")
        _as_postgres("initdb", "-D", str(data), *initdb_options)
        cluster = PrivateCluster(data, free_port())
        options = f"-p {cluster.port} -k {root} -c listen_addresses=127.0.0.1"
        cluster.ctl("-o", options, "start")
        try:
            yield cluster
        finally:
            _as_postgres("pg_ctl", "-D", str(data), "-m", "immediate", "stop", check=False)
    finally:
        shutil.rmtree(root, ignore_errors=True)


def test_postgres_restarted_under_load_loses_nothing_accepted_and_safety_goes_on(
    tmp_path: Path,
) -> None:
    with private_cluster() as cluster:
        settings = hub_settings(
            tmp_path, database_url=cluster.url, telemetry_batch_size=20, spool_retry_s=0.2
        )
        with (
            running_hub(settings) as base,
            api_client(base, access_token(base, "admin", ADMIN_PASSWORD)) as api,
        ):
            agent_token = api.post("/api/v1/vehicles/v1/agent-tokens").json()["token"]
            with scripted_agent(base, "v1", agent_token) as agent:
                with streaming(agent, RATE_HZ) as stream:
                    poll_until(lambda: len(stored(api)) > 50, 30, "samples stored")

                    cluster.ctl("-m", "immediate", "stop")  # a crash
                    degraded(api, "the database away")
                    # The live fleet and the safety commands need no database.
                    safety_commands_go_through(api, agent)
                    assert api.get("/api/v1/health").json()["telemetry_backlog"] > 0

                    options = f"-p {cluster.port} -k {cluster.directory.parent}"
                    cluster.ctl("-o", f"{options} -c listen_addresses=127.0.0.1", "start")
                    poll_until(
                        lambda: api.get("/api/v1/health").json()["status"] == "ok",
                        60,
                        "/health to report the database back",
                    )
                    # A fast restart under the same load (a minor-version upgrade, say).
                    cluster.ctl("-m", "fast", "restart")
                    time.sleep(1)  # a second of load after the restart, not a sync
                everything_stored(api, stream.sent)


def test_an_agent_reconnecting_while_postgres_is_down_is_served_and_commanded(
    tmp_path: Path,
) -> None:
    """A vehicle the store knows may reconnect during the outage (its operators may need
    to land it): it is welcomed and stays connected, and a landing reaches it."""
    with private_cluster() as cluster:
        settings = hub_settings(tmp_path, database_url=cluster.url, spool_retry_s=0.2)
        with (
            running_hub(settings) as base,
            api_client(base, access_token(base, "admin", ADMIN_PASSWORD)) as api,
        ):
            agent_token = api.post("/api/v1/vehicles/v1/agent-tokens").json()["token"]
            with scripted_agent(base, "v1", agent_token) as agent:
                agent.send(telemetry_frame(0))
                poll_until(lambda: stored(api) == [0], 30, "the vehicle known to the store")
            cluster.ctl("-m", "immediate", "stop")
            with scripted_agent(base, "v1", agent_token) as agent:
                for name in ("land", "rtl"):
                    with answering(agent) as received:
                        answer = api.post("/api/v1/vehicles/v1/commands", json={"name": name})
                        assert answer.status_code == 200, answer.text
                        assert answer.json()["outcome"]["status"] == "accepted"
                    assert [command["name"] for command in received] == [name]
                assert api.get("/api/v1/vehicles").json()[0]["connected"] is True
