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
import threading
from collections.abc import Iterator
from pathlib import Path

import httpx
import pytest

from tests.conftest import ADMIN_PASSWORD, hub_settings
from tests.helpers import access_token, api_client, poll_until, running_hub
from tests.integration.test_database_outage import answering
from tests.integration.test_hub_bad_input import _telemetry, scripted_agent

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


def _stored(api: httpx.Client) -> list[int]:
    page = api.get("/api/v1/vehicles/v1/telemetry", params={"start": 0, "limit": 10000})
    if page.status_code == 503:
        return []
    page.raise_for_status()
    return sorted(sample["seq"] for sample in page.json()["samples"])


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
            sent = 0
            stop = threading.Event()

            def stream() -> None:
                nonlocal sent
                while not stop.is_set():
                    agent.send(_telemetry(sent))
                    sent += 1
                    stop.wait(1 / RATE_HZ)  # the agent's sampling rate

            streamer = threading.Thread(target=stream, daemon=True)
            streamer.start()
            filler = small_disk / "filler"
            try:
                poll_until(lambda: len(_stored(api)) > 50, 30, "samples stored")
                _fill(filler)
                health = poll_until(
                    lambda: (h := api.get("/api/v1/health").json())["status"] == "degraded" and h,
                    30,
                    "/health to report the full disk",
                )
                assert health["database_available"] is False
                assert health["telemetry_backlog"] > 0  # held, not dropped
                assert api.get("/api/v1/vehicles").status_code == 200
                for name in ("land", "rtl", "hold"):
                    with answering(agent) as received:
                        answer = api.post("/api/v1/vehicles/v1/commands", json={"name": name})
                        assert answer.status_code == 200, answer.text
                        assert answer.json()["outcome"]["status"] == "accepted"
                    assert [command["name"] for command in received] == [name]
                os.unlink(filler)  # the operator frees space
                poll_until(
                    lambda: api.get("/api/v1/health").json()["status"] == "ok",
                    60,
                    "/health to report the store back",
                )
            finally:
                stop.set()
                streamer.join(10)
                with contextlib.suppress(FileNotFoundError):
                    os.unlink(filler)
            poll_until(
                lambda: (
                    api.get("/api/v1/health").json()["rows_spooled"] == 0
                    and len(_stored(api)) >= sent
                ),
                60,
                f"all {sent} samples and the spooled rows stored",
            )
            assert _stored(api) == list(range(sent)), "a sample is missing or stored twice"
            assert api.get("/api/v1/health").json()["rows_lost"] == 0
            commands = api.get("/api/v1/commands", params={"vehicle_id": "v1"}).json()
            assert sorted(c["name"] for c in commands["commands"]) == ["hold", "land", "rtl"]
