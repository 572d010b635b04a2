"""The agent↔hub link, cut while the hub itself stays up: a link that flaps every few
seconds, then one cut for 30 s. Real processes; the agent reaches the hub through a TCP
proxy the test cuts (connections dropped, new ones refused, as an unplugged modem).

Guaranteed: the configured failsafe runs once the link has been gone for its timeout
(and not on a short flap), the backlog is replayed in order when the link is back, and
every sample is stored exactly once.

The simulator runs at 4x and the agent's failsafe and reconnect waits on its clock
(vehicle_agents/sensors/paced_clock.py), so the flaps and the cut are the autopilot's seconds
too: a 30 s cut of the simulated flight lasts 7.5 s of the test's.
"""

from __future__ import annotations

import dataclasses
import sqlite3
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from gcs.launcher import FleetPlan, LocalFleet, free_port
from tests.support.api import access_token, api_client
from tests.support.hubs import TEST_HUB_ENV
from tests.support.processes import spilled_frames
from tests.support.settling import take_off
from tests.support.tcp_proxy import CuttableProxy
from tests.support.waiting import poll_until
from tests.support.watcher import FleetWatcher, connected, ready

pytestmark = [pytest.mark.integration, pytest.mark.slow]

VEHICLE = "sim_1"
SPEEDUP = 4.0
# In the autopilot's seconds, as the agent counts them; the test waits them out in its own.
FAILSAFE_S = 5
FLAPS = 5
FLAP_DOWN_S, FLAP_UP_S = 1.0, 2.0
OUTAGE_S = 30.0
OUTAGE_WALL_S = OUTAGE_S / SPEEDUP  # the telemetry is sampled and stamped on the wall clock


@pytest.fixture
def proxied_fleet(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> Iterator[tuple[LocalFleet, CuttableProxy]]:
    # The agent reads these from its environment, as from a systemd unit.
    monkeypatch.setenv("GCS_AGENT_HUB_FAILSAFE_ACTION", "rtl")
    monkeypatch.setenv("GCS_AGENT_HUB_FAILSAFE_TIMEOUT_S", str(FAILSAFE_S))
    plan = FleetPlan(vehicles=1, port=free_port(), data_dir=tmp_path, speedup=SPEEDUP)
    with LocalFleet(plan) as fleet:
        plan.data_dir.mkdir(parents=True, exist_ok=True)
        fleet.log_dir.mkdir(parents=True, exist_ok=True)
        fleet.start_hub(TEST_HUB_ENV)
        fleet.wait_until_ready()
        with CuttableProxy(("127.0.0.1", plan.port)) as proxy:
            # The vehicle's agent dials the proxy; everything else the hub directly.
            fleet.plan = dataclasses.replace(plan, port=proxy.port)
            fleet.start_vehicle(0)
            fleet.plan = plan
            yield fleet, proxy


def _stored(fleet: LocalFleet, query: str) -> list[tuple[int, ...]]:
    with sqlite3.connect(fleet.plan.data_dir / "gcs.sqlite3", timeout=10) as db:
        return db.execute(query).fetchall()


def test_a_flapping_link_then_a_30_s_cut_runs_the_failsafe_and_replays_in_order_once(
    proxied_fleet: tuple[LocalFleet, CuttableProxy],
) -> None:
    fleet, proxy = proxied_fleet
    base = fleet.plan.hub_http
    token = access_token(base, "admin", fleet.plan.admin_password)
    with FleetWatcher(base, token) as watcher, api_client(base, token) as api:
        watcher.wait_until(ready(VEHICLE), 60, f"{VEHICLE} ready")
        take_off(api, watcher, VEHICLE, 15, above=12)

        # Flapping: short drops, each shorter than the failsafe's timeout.
        for _ in range(FLAPS):
            proxy.cut()
            time.sleep(FLAP_DOWN_S / SPEEDUP)  # the drop itself, not a sync
            proxy.start()
            time.sleep(FLAP_UP_S / SPEEDUP)  # the link's up time, not a sync
        watcher.wait_until(connected(VEHICLE), 30, "the agent back after the flaps")
        watcher.wait_until(
            lambda v: v[VEHICLE]["state"]["mode"] == "GUIDED" and v[VEHICLE]["state"]["armed"],
            10,
            "the vehicle still hovering in GUIDED (no failsafe on a flap)",
        )

    # A 30 s cut: the failsafe runs on board while the hub cannot hear of it.
    proxy.cut()
    cut_at = time.time()
    poll_until(
        lambda: any(
            frame.kind == "event" and "commanded RTL" in frame.body
            for frame in spilled_frames(fleet, VEHICLE)
        ),
        FAILSAFE_S + 20,
        "the agent to command RTL on the lost link",
    )
    time.sleep(max(0.0, cut_at + OUTAGE_WALL_S - time.time()))  # the outage, not a sync
    proxy.start()

    target = int((time.time() - cut_at + 3) * fleet.plan.telemetry_rate_hz)

    def seqs() -> list[int]:
        rows = _stored(fleet, f"SELECT seq FROM telemetry WHERE vehicle_id = '{VEHICLE}'")
        return sorted(seq for (seq,) in rows)

    poll_until(
        lambda: (s := seqs()) and s[-1] >= target and len(s) == s[-1] + 1,
        60,
        "the backlog replayed and stored",
    )
    fleet.stop()  # agents first: what they sent last is stored before the hub stops

    rows = _stored(
        fleet,
        f"SELECT seq, time FROM telemetry WHERE vehicle_id = '{VEHICLE}' ORDER BY seq",
    )
    numbers = [seq for seq, _ in rows]
    assert numbers == list(range(len(numbers))), "a sample is missing or stored twice"
    # In order: the store took the samples in the order the agent took them (a backlog
    # replayed out of order would be written out of order).
    arrival = [
        seq
        for (seq,) in _stored(
            fleet, f"SELECT seq FROM telemetry WHERE vehicle_id = '{VEHICLE}' ORDER BY rowid"
        )
    ]
    assert arrival == numbers, "the backlog was stored out of order"
    times = [when for _, when in rows]
    during = [when for when in times if cut_at + 1 < when < cut_at + OUTAGE_WALL_S - 1]
    assert len(during) >= (OUTAGE_WALL_S - 2) * fleet.plan.telemetry_rate_hz * 0.9
    texts = [text for (text,) in _stored(fleet, "SELECT text FROM events WHERE kind = 'failsafe'")]
    assert sum(f"hub link lost for {FAILSAFE_S} s: commanded RTL" in t for t in texts) == 1, texts
    assert any("on losing it the agent commanded RTL" in text for text in texts), texts
