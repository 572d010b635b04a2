"""The hub's SQLite disk fills up: its data folder is a real, small file system (a tmpfs
of a few MiB mounted for the test; root only), filled to the last block while an agent
streams telemetry.

Guaranteed: the live service and the safety commands go on, /health reports the store
as unavailable, and every sample the hub accepted is stored, each once, when space is
freed again (the writer holds them meanwhile, as through a database outage); so are the
audit and command-log rows of the commands, which the spool holds in memory when its
own file, on the same full disk, cannot take them.
"""

from __future__ import annotations

import contextlib
import os
import subprocess
import tempfile
from collections.abc import Iterator
from pathlib import Path

import pytest

from tests.conftest import ADMIN_PASSWORD, hub_settings
from tests.support.agents import scripted_agent
from tests.support.api import access_token, api_client
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

SIZE = "6m"
RATE_HZ = 100


@pytest.fixture
def small_disk() -> Iterator[Path]:
    """A tmpfs of ``SIZE``, unmounted (and its folder removed) after the test."""
    mountpoint = Path(tempfile.mkdtemp(prefix="gcs-full-"))
    mounted = subprocess.run(
        ["mount", "-t", "tmpfs", "-o", f"size={SIZE},mode=0700", "tmpfs", str(mountpoint)],
        capture_output=True,
    )
    if mounted.returncode != 0:
        mountpoint.rmdir()
        pytest.skip(f"cannot mount a small file system: {mounted.stderr.decode().strip()}")
    try:
        yield mountpoint
    finally:
        subprocess.run(["umount", "-l", str(mountpoint)], capture_output=True)
        with contextlib.suppress(OSError):
            mountpoint.rmdir()


def _fill(path: Path) -> None:
    """Write until the file system refuses another byte (unbuffered: each write is one)."""
    descriptor = os.open(path, os.O_WRONLY | os.O_CREAT, 0o600)
    try:
        for size in (65536, 4096, 1):
            with contextlib.suppress(OSError):  # ENOSPC: full, at this size
                while True:
                    os.write(descriptor, b"\0" * size)
    finally:
        os.close(descriptor)


def test_a_full_disk_under_the_store_loses_nothing_accepted_and_safety_goes_on(
    small_disk: Path,
) -> None:
    settings = hub_settings(small_disk, telemetry_batch_size=20, spool_retry_s=0.2)
    with (
        running_hub(settings) as base,
        api_client(base, access_token(base, "admin", ADMIN_PASSWORD)) as api,
    ):
        agent_token = api.post("/api/v1/vehicles/v1/agent-tokens").json()["token"]
        with scripted_agent(base, "v1", agent_token) as agent:
            filler = small_disk / "filler"
            try:
                with streaming(agent, RATE_HZ) as stream:
                    poll_until(lambda: len(stored(api)) > 50, 30, "samples stored")
                    _fill(filler)
                    health = degraded(api, "the full disk")
                    assert health["telemetry_backlog"] > 0  # held, not dropped
                    safety_commands_go_through(api, agent)
                    os.unlink(filler)  # the operator frees space
                    poll_until(
                        lambda: api.get("/api/v1/health").json()["status"] == "ok",
                        60,
                        "/health to report the store back",
                    )
            finally:
                with contextlib.suppress(FileNotFoundError):
                    os.unlink(filler)
            everything_stored(api, stream.sent)
            assert api.get("/api/v1/health").json()["rows_lost"] == 0
