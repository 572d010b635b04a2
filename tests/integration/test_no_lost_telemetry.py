"""No lost telemetry: the hub dies mid-mission and every sample still arrives, once.

The hub is killed (SIGKILL, no flush) for 30 s while a simulated copter flies a mission.
The agent keeps its telemetry on disk meanwhile and replays it when the hub is back;
whatever the dead hub had received but not committed comes again too, because the agent
forgets a frame only once the hub's ack says it is stored.
"""

from __future__ import annotations

import sqlite3
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from gcs.launcher import LocalFleet
from tests.support.api import access_token, api_client
from tests.support.hubs import TEST_HUB_ENV
from tests.support.processes import running_fleet, spilled_frames
from tests.support.waiting import poll_until
from tests.support.watcher import FleetWatcher, ready

pytestmark = [pytest.mark.integration, pytest.mark.slow]

VEHICLE = "sim_1"
OUTAGE_S = 30.0
TAKEOFF = mavlink2.MAV_CMD_NAV_TAKEOFF
WAYPOINT = mavlink2.MAV_CMD_NAV_WAYPOINT
LOITER_TIME = mavlink2.MAV_CMD_NAV_LOITER_TIME
RTL = mavlink2.MAV_CMD_NAV_RETURN_TO_LAUNCH


@pytest.fixture
def one_vehicle(tmp_path: Path) -> Iterator[LocalFleet]:
    with running_fleet(tmp_path, vehicles=1, speedup=4.0) as fleet:
        yield fleet


def _stored(fleet: LocalFleet, query: str) -> list[tuple[Any, ...]]:
    """Read the hub's SQLite store directly: the ground truth, not an API's view of it."""
    with sqlite3.connect(fleet.plan.data_dir / "gcs.sqlite3", timeout=10) as db:
        return db.execute(query).fetchall()


def _telemetry_seqs(fleet: LocalFleet) -> list[int]:
    rows = _stored(fleet, f"SELECT seq FROM telemetry WHERE vehicle_id = '{VEHICLE}'")
    return sorted(seq for (seq,) in rows)


def _long_mission(lat: float, lon: float) -> list[dict[str, Any]]:
    north = 1 / 111_320
    return [
        {"command": TAKEOFF, "alt": 15},
        {"command": WAYPOINT, "lat": lat + 150 * north, "lon": lon, "alt": 15},
        {"command": LOITER_TIME, "param1": 60, "lat": lat + 150 * north, "lon": lon, "alt": 15},
        {"command": WAYPOINT, "lat": lat, "lon": lon, "alt": 15},
        {"command": RTL},
    ]


def test_hub_killed_for_30_s_mid_mission_loses_and_duplicates_nothing(
    one_vehicle: LocalFleet,
) -> None:
    fleet = one_vehicle
    base = fleet.plan.hub_http
    token = access_token(base, "admin", fleet.plan.admin_password)
    with FleetWatcher(base, token) as watcher, api_client(base, token) as api:
        watcher.wait_until(ready(VEHICLE), 60, f"{VEHICLE} ready")
        here = watcher.state(VEHICLE)
        mission = api.post(
            f"/api/v1/vehicles/{VEHICLE}/mission",
            json={"items": _long_mission(here["lat"], here["lon"])},
        )
        assert mission.status_code == 200, mission.text
        commands = f"/api/v1/vehicles/{VEHICLE}/commands"
        for command in ({"name": "set_mode", "mode": "GUIDED"}, {"name": "arm"}):
            assert api.post(commands, json=command).json()["outcome"]["status"] == "accepted"
        auto = api.post(commands, json={"name": "set_mode", "mode": "AUTO"})
        assert auto.json()["outcome"]["status"] == "accepted", auto.text
        watcher.wait_until(lambda v: (v[VEHICLE]["state"]["alt_rel"] or 0) > 10, 60, "climb")

    killed_at = time.time()
    fleet.kill("hub")
    deadline = time.monotonic() + OUTAGE_S
    # Meanwhile the agent spills to disk (checked, not assumed: the file fills up).
    poll_until(lambda: len(spilled_frames(fleet, VEHICLE)) > 100, OUTAGE_S, "the outbox to spill")
    time.sleep(max(0.0, deadline - time.monotonic()))  # the outage itself, not a sync
    restarted_at = time.time()
    fleet.start_hub(TEST_HUB_ENV)
    fleet.wait_until_ready()

    # Everything the agent produced up to now must arrive, without holes.
    target = int((time.time() - killed_at + 5) * fleet.plan.telemetry_rate_hz)
    poll_until(
        lambda: (
            (seqs := _telemetry_seqs(fleet)) and seqs[-1] >= target and len(seqs) == seqs[-1] + 1
        ),
        60,
        "the replayed outbox to be stored",
    )
    fleet.stop()  # agents first: what they sent last is stored before the hub stops

    seqs = _telemetry_seqs(fleet)
    assert seqs == list(range(len(seqs))), "a telemetry sequence number is missing"
    streams = _stored(
        fleet, f"SELECT DISTINCT stream_id FROM telemetry WHERE vehicle_id = '{VEHICLE}'"
    )
    assert len(streams) == 1
    # The outage is covered by samples taken while the vehicle flew, replayed from disk.
    during = _stored(
        fleet,
        "SELECT count(*), min(alt_rel), max(armed) FROM telemetry "
        f"WHERE vehicle_id = '{VEHICLE}' AND time > {killed_at + 1} AND time < {restarted_at - 1}",
    )[0]
    count, lowest, armed = during
    assert count >= (OUTAGE_S - 2) * fleet.plan.telemetry_rate_hz * 0.9
    assert lowest > 5, "the vehicle was flying throughout the outage"
    assert armed == 1
    # The agent's own events (not the hub's, which are numbered after the samples they
    # were derived from) are complete as well, including the failsafe's report.
    (stream,) = streams[0]
    events = _stored(
        fleet, f"SELECT seq, text FROM events WHERE stream_id = '{stream}' ORDER BY seq"
    )
    assert [seq for seq, _ in events] == list(range(len(events)))
    assert any("hub link restored after" in text for _, text in events)


def test_an_agent_restarted_during_an_outage_replays_its_earlier_run(
    one_vehicle: LocalFleet,
) -> None:
    """The agent dies (SIGKILL) while the hub is away: what it had spilled to disk is
    sent by its next run, under the earlier run's stream, once the hub is back."""
    fleet = one_vehicle
    base = fleet.plan.hub_http
    token = access_token(base, "admin", fleet.plan.admin_password)
    with FleetWatcher(base, token) as watcher:
        watcher.wait_until(ready(VEHICLE), 60, f"{VEHICLE} ready")
    fleet.kill("hub")
    poll_until(lambda: len(spilled_frames(fleet, VEHICLE)) > 60, 30, "the outbox to spill")
    fleet.kill("agent_1")
    spilled = [f for f in spilled_frames(fleet, VEHICLE) if f.kind == "telemetry"]
    (earlier_run,) = {f.stream_id for f in spilled}
    spilled_up_to = max(f.seq for f in spilled)
    fleet.start_agent(0, fleet.sim_ports[0])
    fleet.start_hub(TEST_HUB_ENV)
    fleet.wait_until_ready()

    def earlier_run_stored() -> list[int]:
        rows = _stored(fleet, f"SELECT seq FROM telemetry WHERE stream_id = '{earlier_run}'")
        return sorted(seq for (seq,) in rows)

    poll_until(
        lambda: (seqs := earlier_run_stored()) and seqs[-1] >= spilled_up_to,
        60,
        "the earlier run's frames to be stored",
    )
    # Everything the earlier run had stored or spilled is there, each once.
    assert earlier_run_stored()[: spilled_up_to + 1] == list(range(spilled_up_to + 1))
    runs = _stored(
        fleet, f"SELECT DISTINCT stream_id FROM telemetry WHERE vehicle_id = '{VEHICLE}'"
    )
    assert len(runs) == 2, "the new run streams under its own name"

    def earlier_run_on_disk() -> int:
        return sum(f.stream_id == earlier_run for f in spilled_frames(fleet, VEHICLE))

    # The hub's acks name the earlier run too: the agent forgets what is stored.
    poll_until(lambda: earlier_run_on_disk() == 0, 30, "the stored frames to leave the disk")
