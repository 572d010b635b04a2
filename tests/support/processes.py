"""A fleet, or one agent, as real processes on loopback; what an agent spilled to disk."""

from __future__ import annotations

import os
import sqlite3
import subprocess
import sys
from collections.abc import Iterator, Sequence
from contextlib import ExitStack, contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from gcs.launcher import FleetPlan, LocalFleet, end_with_parent, free_port
from tests.support.hubs import TEST_HUB_ENV, seed_database


@contextmanager
def running_fleet(data_dir: Path, **plan: Any) -> Iterator[LocalFleet]:
    """Hub, simulators and agents as real processes on loopback, started and ready;
    ``plan`` is what differs from `FleetPlan`'s defaults (vehicles, speedup, frames...).
    The hub starts on a copy of the migrated template database (its migration then finds
    nothing to do)."""
    seed_database(data_dir)
    with LocalFleet(FleetPlan(port=free_port(), data_dir=data_dir, **plan)) as fleet:
        fleet.start(TEST_HUB_ENV)
        fleet.wait_until_ready()
        yield fleet


@contextmanager
def agent_process(
    hub: str,
    token: str,
    vehicle_id: str,
    fcu_port: int,
    log_dir: Path | None = None,
    extra_args: Sequence[str] = (),
) -> Iterator[subprocess.Popen[bytes]]:
    """`gcs agent` as a process between a flight controller on loopback TCP at
    ``fcu_port`` and the hub
    at ``hub`` (its http:// URL), with ``extra_args`` added to its command line; its
    output goes to ``log_dir/<vehicle_id>.log`` if given, else where the test's goes."""
    with ExitStack() as stack:
        log = (
            None
            if log_dir is None
            else stack.enter_context((log_dir / f"{vehicle_id}.log").open("wb"))
        )
        agent = subprocess.Popen(
            [
                sys.executable,
                "-m",
                "gcs",
                "agent",
                "--fcu",
                f"tcp:127.0.0.1:{fcu_port}",
                "--hub",
                hub.replace("http://", "ws://"),
                "--vehicle-id",
                vehicle_id,
                *extra_args,
            ],
            env={**os.environ, "GCS_AGENT_TOKEN": token},
            stdout=log,
            stderr=None if log is None else subprocess.STDOUT,
            preexec_fn=end_with_parent(),  # never outlives a killed pytest
        )
        try:
            yield agent
        finally:
            agent.terminate()
            agent.wait(10)


@dataclass(frozen=True)
class SpilledFrame:
    stream_id: str
    kind: str
    seq: int
    body: str


def spilled_frames(fleet: LocalFleet, vehicle: str) -> list[SpilledFrame]:
    """What the agent of a local fleet keeps on disk for the hub, oldest first (nothing
    before it first spills)."""
    path = fleet.plan.data_dir / "onboard" / vehicle / f"{vehicle}.outbox.sqlite"
    if not path.exists():
        return []
    with sqlite3.connect(path, timeout=5) as db:
        rows = db.execute("SELECT stream_id, kind, seq, body FROM frames ORDER BY id").fetchall()
    return [SpilledFrame(*row) for row in rows]
