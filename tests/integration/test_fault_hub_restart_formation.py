"""The hub killed (SIGKILL) and restarted while a formation flies: real hub, simulators
and agents; the simulators at 4x, the formation flown in their seconds (the hub's
GCS_FLEET_SPEEDUP, the followers' paced clocks: vehicle_agents/sensors/paced_clock.py).

Guaranteed: the followers hold where they are once the leader's relayed state goes stale
(their agents do it, with no hub), the restarted hub does not resume the formation but
records it as stopped because the hub restarted (never listed as running for ever), and
every vehicle's telemetry is stored without a hole and without a duplicate.
"""

from __future__ import annotations

import sqlite3
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from common.geodesy import LocalFrame
from gcs.launcher import LocalFleet
from tests.support.api import access_token, api_client
from tests.support.formations import ALTITUDES, LEADER, LEFT, RIGHT, _request, take_off_all
from tests.support.hubs import TEST_HUB_ENV
from tests.support.processes import running_fleet, spilled_frames
from tests.support.waiting import poll_until
from tests.support.watcher import FleetWatcher, ready

pytestmark = [pytest.mark.integration, pytest.mark.slow]

SPEEDUP = 4.0
OUTAGE_S = 10.0  # of the vehicles' flight


@pytest.fixture
def airborne(tmp_path: Path) -> Iterator[LocalFleet]:
    with running_fleet(tmp_path, vehicles=3, speedup=SPEEDUP) as fleet:
        yield fleet


def _seqs(fleet: LocalFleet, vehicle: str) -> tuple[int, list[int]]:
    with sqlite3.connect(fleet.plan.data_dir / "gcs.sqlite3", timeout=10) as db:
        rows = db.execute(
            "SELECT stream_id, seq FROM telemetry WHERE vehicle_id = ?", (vehicle,)
        ).fetchall()
    return len({stream for stream, _ in rows}), sorted(seq for _, seq in rows)


def test_a_hub_killed_mid_formation_leaves_followers_holding_and_records_it_stopped(
    airborne: LocalFleet,
) -> None:
    fleet = airborne
    base = fleet.plan.hub_http
    token = access_token(base, "admin", fleet.plan.admin_password)
    with FleetWatcher(base, token) as watcher, api_client(base, token) as api:
        take_off_all(watcher, api, ALTITUDES)
        here = watcher.state(LEADER)
        answer = api.post("/api/v1/formations", json=_request(LocalFrame(here["lat"], here["lon"])))
        assert answer.status_code == 200, answer.text
        formation_id = answer.json()["id"]
        poll_until(
            lambda: api.get(f"/api/v1/formations/{formation_id}").json()["formed_at"],
            60,
            "the followers in their slots",
        )

    killed_at = time.time()
    fleet.kill("hub")
    for follower in (RIGHT, LEFT):
        poll_until(
            lambda f=follower: any(
                frame.kind == "event" and "hold" in frame.body.lower()
                for frame in spilled_frames(fleet, f)
            ),
            15,
            f"{follower} to hold on its own",
        )
    time.sleep(max(0.0, killed_at + OUTAGE_S / SPEEDUP - time.time()))  # the outage, not a sync
    fleet.start_hub(TEST_HUB_ENV)
    fleet.wait_until_ready()

    token = access_token(base, "admin", fleet.plan.admin_password)
    with FleetWatcher(base, token) as watcher, api_client(base, token) as api:
        # Still in the air, holding: not drifting, not falling.
        for follower in (RIGHT, LEFT):
            watcher.wait_until(
                lambda v, f=follower: (
                    ready(f)(v)
                    and v[f]["state"]["armed"]
                    and (v[f]["state"]["groundspeed"] or 0) < 0.5
                    and abs((v[f]["state"]["alt_rel"] or 0) - ALTITUDES[f]) < 1.5
                ),
                30,
                f"{follower} holding in the air",
            )
        stored = {f["id"]: f for f in api.get("/api/v1/formations").json()["formations"]}
        assert stored[formation_id]["stop_reason"] == "stopped: the hub restarted while it flew"
        assert stored[formation_id]["stopped"] is not None
        # Its members are free for the next one (the leader's first state since the
        # restart may come after the followers'; the feed sends each vehicle's own).
        watcher.wait_until(
            lambda v: ready(LEADER)(v) and v[LEADER]["state"].get("lat") is not None,
            30,
            "the leader's position since the restart",
        )
        here = watcher.state(LEADER)
        again = api.post("/api/v1/formations", json=_request(LocalFrame(here["lat"], here["lon"])))
        assert again.status_code == 200, again.text
        api.post(f"/api/v1/formations/{again.json()['id']}/stop")

        target = int((time.time() - killed_at) * fleet.plan.telemetry_rate_hz)
        for vehicle in ALTITUDES:
            poll_until(
                lambda v=vehicle: (s := _seqs(fleet, v)[1]) and s[-1] >= target,
                60,
                f"{vehicle}'s replayed outbox stored",
            )
    fleet.stop()
    for vehicle in ALTITUDES:
        streams, seqs = _seqs(fleet, vehicle)
        assert streams == 1
        assert seqs == list(range(len(seqs))), f"{vehicle}: a sample missing or stored twice"
