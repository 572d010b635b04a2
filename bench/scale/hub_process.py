"""The hub under load: started here (or given), its agents enrolled, its store counted."""

from __future__ import annotations

import contextlib
import os
import shutil
import subprocess
import sys
import tempfile
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import httpx
from sqlalchemy import create_engine, text

from bench.scale.agents import vehicle_id
from gcs.launcher import free_port

ADMIN_PASSWORD = "bench-admin-password"


@contextlib.contextmanager
def started_hub(
    vehicles: int, database: str | None, tokens: dict[int, str], log_path: Path
) -> Iterator[tuple[str, int]]:
    data_dir = Path(tempfile.mkdtemp(prefix="bench-scale-"))
    port = free_port()
    env = {
        **os.environ,
        "GCS_ENVIRONMENT": "development",
        "GCS_ADMIN_PASSWORD": ADMIN_PASSWORD,
        "GCS_VIZ_ENABLED": "false",
        "GCS_AGENT_TOKENS": ",".join(f"{vehicle_id(i)}={t}" for i, t in tokens.items()),
        # Every agent and dashboard is a connection; the default 1,000 is a guard, not a
        # measure of what the hub holds.
        "GCS_MAX_CONNECTIONS": str(max(1000, 2 * vehicles + 100)),
        "GCS_COMMANDS_PER_SECOND": "1000",
    }
    if database:
        env["DATABASE_URL"] = database
    gcs = shutil.which("gcs", path=str(Path(sys.executable).parent)) or "gcs"
    with log_path.open("wb") as log:
        process = subprocess.Popen(
            [gcs, "hub", "--host", "127.0.0.1", "--port", str(port), "--data-dir", str(data_dir)],
            env=env,
            stdout=log,
            stderr=subprocess.STDOUT,
        )
    url = f"http://127.0.0.1:{port}"
    try:
        deadline = time.monotonic() + 120
        while True:
            with contextlib.suppress(httpx.HTTPError):
                if httpx.get(f"{url}/api/v1/health", timeout=2).status_code == 200:
                    break
            if process.poll() is not None or time.monotonic() > deadline:
                raise RuntimeError(f"the hub did not start: see {log_path}")
            time.sleep(0.2)
        yield url, process.pid
    finally:
        process.terminate()
        try:
            process.wait(30)
        except subprocess.TimeoutExpired:
            process.kill()
        shutil.rmtree(data_dir, ignore_errors=True)


def hub_data_dir(pid: int) -> Path:
    """The data folder of the hub started here (its SQLite file is there)."""
    args = Path(f"/proc/{pid}/cmdline").read_bytes().decode().split("\0")
    return Path(args[args.index("--data-dir") + 1])


def stored_counts(database_url: str) -> dict[str, tuple[int, int]]:
    """Per bench vehicle: rows stored, and distinct sequence numbers among them."""
    engine = create_engine(database_url)
    try:
        with engine.connect() as connection:
            rows = connection.execute(
                text(
                    "SELECT vehicle_id, count(*), count(DISTINCT seq) FROM telemetry "
                    "WHERE vehicle_id LIKE 'bench_%' GROUP BY vehicle_id"
                )
            ).all()
    finally:
        engine.dispose()
    return {row[0]: (int(row[1]), int(row[2])) for row in rows}


def stored_after_drain(
    database_url: str, agent_results: list[dict[str, Any]]
) -> dict[str, tuple[int, int]]:
    """The store's counts once the hub has written what it holds: an agent that gave up
    waiting for its acks left frames in the hub's queue, which are stored, not lost."""
    sent = sum(sum(part["sent"].values()) for part in agent_results)
    counts = stored_counts(database_url)
    last_progress, stored = time.monotonic(), sum(c[1] for c in counts.values())
    while stored < sent and time.monotonic() - last_progress < 10:
        time.sleep(1)  # polling: the store announces nothing
        counts = stored_counts(database_url)
        if (now_stored := sum(c[1] for c in counts.values())) > stored:
            last_progress, stored = time.monotonic(), now_stored
    return counts


def enrol(urls: list[str], password: str, vehicles: int) -> dict[int, str]:
    """Tokens for an existing hub, through its admin API."""
    admin = admin_token(urls[0], password)
    tokens = {}
    with httpx.Client(
        base_url=urls[0], headers={"Authorization": f"Bearer {admin}"}, timeout=30
    ) as api:
        for index in range(vehicles):
            response = api.post(f"/api/v1/vehicles/{vehicle_id(index)}/agent-tokens")
            response.raise_for_status()
            tokens[index] = response.json()["token"]
    return tokens


def admin_token(url: str, password: str) -> str:
    response = httpx.post(
        f"{url}/api/v1/auth/token", data={"username": "admin", "password": password}, timeout=30
    )
    response.raise_for_status()
    token: str = response.json()["access_token"]
    return token
