"""An agent killed (SIGKILL: no flush, no goodbye) while its vehicle flies, and started
again: it re-attaches to the same flight controller and the hub serves the vehicle again.

Numbering is per agent run: each run has its own stream id and numbers its samples from
0, so (stream, seq) never repeats across restarts, and the store holds each run without a
hole. What the killed run never had acknowledged it held only in memory (the disk takes
frames only while the hub is away), and nothing was sampled while no agent ran: the hub
records that gap as an ``agent_restart`` event naming the run that ended, its last
sample and the run that follows.
"""

from __future__ import annotations

import sqlite3
from collections.abc import Iterator
from pathlib import Path

import pytest

from gcs.launcher import LocalFleet
from tests.support.api import access_token, api_client, send_command
from tests.support.processes import running_fleet
from tests.support.settling import take_off
from tests.support.waiting import poll_until
from tests.support.watcher import FleetWatcher, ready

pytestmark = [pytest.mark.integration, pytest.mark.slow]

VEHICLE = "sim_1"


@pytest.fixture
def one_vehicle(tmp_path: Path) -> Iterator[LocalFleet]:
    with running_fleet(tmp_path, vehicles=1, speedup=4.0) as fleet:
        yield fleet


def _runs(fleet: LocalFleet) -> dict[str, list[int]]:
    """Each agent run's stored sample numbers, in order; runs by their first sample."""
    with sqlite3.connect(fleet.plan.data_dir / "gcs.sqlite3", timeout=10) as db:
        rows = db.execute(
            "SELECT stream_id, seq FROM telemetry WHERE vehicle_id = ? ORDER BY time, seq",
            (VEHICLE,),
        ).fetchall()
    runs: dict[str, list[int]] = {}
    for stream, seq in rows:
        runs.setdefault(stream, []).append(seq)
    return {stream: sorted(seqs) for stream, seqs in runs.items()}


def test_an_agent_killed_mid_flight_reattaches_and_the_hub_records_the_gap(
    one_vehicle: LocalFleet,
) -> None:
    fleet = one_vehicle
    base = fleet.plan.hub_http
    token = access_token(base, "admin", fleet.plan.admin_password)
    with FleetWatcher(base, token) as watcher, api_client(base, token) as api:
        watcher.wait_until(ready(VEHICLE), 60, f"{VEHICLE} ready")
        take_off(api, watcher, VEHICLE, 15, above=12)

        fleet.kill("agent_1")
        watcher.wait_until(lambda v: not v[VEHICLE]["connected"], 30, "the hub to see it go")
        fleet.start_agent(0, fleet.sim_ports[0])
        # Re-attached to the same flight controller, which flew on meanwhile.
        watcher.wait_until(
            lambda v: (
                v[VEHICLE]["connected"]
                and v[VEHICLE]["state"]["armed"]
                and (v[VEHICLE]["state"]["alt_rel"] or 0) > 12
            ),
            60,
            "the restarted agent to report the flying vehicle",
        )
        # ...and commands reach it again.
        assert send_command(api, VEHICLE, name="land")["status"] == "accepted"

        def restart_events() -> list[str]:
            params = {"vehicle_id": VEHICLE, "kind": "agent_restart"}
            return [e["text"] for e in api.get("/api/v1/events", params=params).json()["events"]]

        (text,) = poll_until(restart_events, 20, "the restart to be recorded")
        poll_until(lambda: len(_runs(fleet)) == 2, 20, "the new run's samples stored")
    fleet.stop()

    runs = _runs(fleet)
    earlier, later = runs  # by the time of their first sample
    for seqs in runs.values():
        assert seqs == list(range(len(seqs))), "a run has a hole or a duplicate"
    assert f"run {earlier} ended with sample {runs[earlier][-1]}" in text
    assert f"run {later}, which starts now" in text
