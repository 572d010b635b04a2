"""A NATS server of the tests' own that requires a login: the shipped
deploy/nats-server.conf, run by the machine's ``nats-server`` on a free loopback port.

The machine's shared server (127.0.0.1:4222) takes anyone; this one proves the login.
"""

from __future__ import annotations

import os
import shutil
import socket
import subprocess
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import pytest

from gcs.launcher import free_port

ROOT = Path(__file__).resolve().parents[2]
SHIPPED_CONFIG = ROOT / "deploy" / "nats-server.conf"
HUB_USER = "gcs-hub"  # the user deploy/nats-server.conf admits


def nats_server_binary() -> str:
    found = shutil.which("nats-server") or shutil.which("nats-server", path="/usr/sbin")
    if found is None:
        if os.environ.get("CI", "").lower() == "true":
            raise RuntimeError("nats-server is missing (apt-get install nats-server)")
        pytest.skip("nats-server is not installed")
    return found


@contextmanager
def nats_server(
    password: str, config: Path = SHIPPED_CONFIG, log_path: Path | None = None
) -> Iterator[str]:
    """Run ``config`` with GCS_BUS_PASSWORD set (quoted, as docker-compose.yml gives
    it); yields its "127.0.0.1:port"."""
    port = free_port()
    log = log_path.open("ab") if log_path is not None else subprocess.DEVNULL
    process = subprocess.Popen(
        [nats_server_binary(), "-c", str(config), "-a", "127.0.0.1", "-p", str(port)],
        stdin=subprocess.DEVNULL,
        stdout=log,
        stderr=subprocess.STDOUT,
        env={"PATH": os.environ.get("PATH", ""), "GCS_BUS_PASSWORD": f'"{password}"'},
    )
    try:
        _wait_for_port(process, port, 10.0)
        yield f"127.0.0.1:{port}"
    finally:
        process.terminate()
        try:
            process.wait(5)
        except subprocess.TimeoutExpired:
            process.kill()
            process.wait(5)
        if log_path is not None and not isinstance(log, int):
            log.close()


def _wait_for_port(process: subprocess.Popen[bytes], port: int, timeout_s: float) -> None:
    deadline = time.monotonic() + timeout_s
    while True:
        if process.poll() is not None:
            raise RuntimeError(f"nats-server exited with {process.returncode}")
        try:
            socket.create_connection(("127.0.0.1", port), timeout=1).close()
            return
        except OSError:
            if time.monotonic() > deadline:
                raise RuntimeError(f"nats-server did not listen on {port}") from None
            time.sleep(0.05)  # polling a port: nothing announces it


def login_refused(address: str, **credentials: str) -> str | None:
    """The server's refusal of a connection with ``credentials`` (user, password), or
    None when it admitted it."""
    import asyncio

    from nats.aio.client import Client as Nats
    from nats.errors import Error as NatsError

    async def attempt() -> str | None:
        async def quiet(_error: Exception) -> None:
            return None  # the refusal is the answer, not a problem to log

        connection = Nats()
        try:
            await connection.connect(
                f"nats://{address}",
                allow_reconnect=False,
                connect_timeout=5,
                error_cb=quiet,
                **credentials,  # type: ignore[arg-type]
            )
        except NatsError as error:
            return str(error)
        finally:
            # Refused or not, the socket closes here, inside the loop that opened it.
            await connection.close()
        return None

    return asyncio.run(attempt())
