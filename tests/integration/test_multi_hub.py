"""Two hub processes sharing PostgreSQL and NATS (docs/deployer.md, "Several hubs").

Real processes on loopback: hub A and hub B on one fresh PostgreSQL database and one
NATS subject prefix of their own, a simulated copter, and its agent, which knows both
hubs (``--hub A --hub-fallback B``) and connects to A first.
"""

from __future__ import annotations

import json
import os
import signal
import socket
import threading
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import psycopg
import pytest
from websockets.sync.client import ClientConnection, connect

from common.geodesy import LocalFrame
from protocol.messages import CLIENT_WS_PATH
from tests.support.api import access_token, api_client, send_command
from tests.support.two_hubs import VEHICLE, TwoHubs, two_hubs
from tests.support.waiting import poll_until
from tests.support.watcher import FleetWatcher, connected, on_the_ground

pytestmark = pytest.mark.integration

NATS_ADDRESS = os.environ.get("GCS_TEST_NATS_ADDRESS", "127.0.0.1:4222")
OPERATOR_PASSWORD = "two-hubs-one-pilot-7"


def _nats_reachable() -> None:
    host, port = NATS_ADDRESS.rsplit(":", 1)
    try:
        socket.create_connection((host, int(port)), timeout=5).close()
    except OSError as error:
        if os.environ.get("CI", "").lower() == "true":
            raise
        pytest.skip(f"NATS is not reachable at {NATS_ADDRESS}: {error}")


@pytest.fixture
def hubs(tmp_path: Path) -> Iterator[TwoHubs]:
    _nats_reachable()
    bus = {"GCS_BUS_URL": f"nats://{NATS_ADDRESS}"}
    with two_hubs(tmp_path, bus, bus) as started:
        yield started


def _psycopg_url(database_url: str) -> str:
    return database_url.replace("postgresql+psycopg://", "postgresql://")


def stored_seqs(database_url: str, vehicle: str) -> dict[str, list[int]]:
    """Each agent stream's stored telemetry numbers, in order."""
    with psycopg.connect(_psycopg_url(database_url)) as db:
        rows = db.execute(
            "SELECT stream_id, seq FROM telemetry WHERE vehicle_id = %s ORDER BY stream_id, seq",
            (vehicle,),
        ).fetchall()
    streams: dict[str, list[int]] = {}
    for stream_id, seq in rows:
        streams.setdefault(stream_id, []).append(int(seq))
    return streams


class Dashboard:
    """A dashboard's live feed: what the hub says, kept as it comes (a thread reads)."""

    def __init__(self, base: str, token: str) -> None:
        url = base.replace("http://", "ws://") + CLIENT_WS_PATH
        self.socket: ClientConnection = connect(
            url, additional_headers={"Authorization": f"Bearer {token}"}, max_queue=None
        )
        self.received: list[dict[str, Any]] = []
        self._reader = threading.Thread(target=self._read, daemon=True)
        self._reader.start()

    def _read(self) -> None:
        try:
            for frame in self.socket:
                self.received.append(json.loads(frame))
        except Exception:
            return

    def control(self, action: str, vehicle: str = VEHICLE) -> dict[str, Any]:
        """Ask for (or give up) the lease; the hub's answer: the lease state or a refusal."""
        asked_at = len(self.received)
        self.socket.send(json.dumps({"type": "control", "vehicle_id": vehicle, "action": action}))

        def answer() -> list[dict[str, Any]]:
            return [
                m
                for m in list(self.received)[asked_at:]
                if m["type"] == "lease_refused"
                or (m["type"] == "lease" and m["vehicle_id"] == vehicle)
            ]

        return poll_until(answer, 30, f"the answer to {action}")[0]

    def stick(self, seq: int, vehicle: str = VEHICLE) -> None:
        """A centred stick frame (the vehicle holds where it is)."""
        axes = {"x": 0, "y": 0, "z": 500, "r": 0, "buttons": 0}
        frame = {"type": "manual", "vehicle_id": vehicle, "seq": seq, "axes": axes}
        self.socket.send(json.dumps({**frame, "source": "keyboard"}))

    def events(self, text: str) -> list[dict[str, Any]]:
        return [
            event
            for message in list(self.received)
            if message["type"] == "events"
            for event in message["events"]
            if text in event["text"]
        ]

    def close(self) -> None:
        self.socket.close()
        self._reader.join(5)


def test_an_agent_on_hub_a_obeys_a_command_sent_through_hub_b(hubs: TwoHubs) -> None:
    with FleetWatcher(hubs.a, hubs.admin_token(hubs.a)) as on_a:
        on_a.wait_until(connected(VEHICLE), 60, f"{VEHICLE} on hub A")
    with (
        FleetWatcher(hubs.b, hubs.admin_token(hubs.b)) as on_b,
        api_client(hubs.b, hubs.admin_token(hubs.b)) as api_b,
    ):
        on_b.wait_until(lambda v: VEHICLE in v and v[VEHICLE]["connected"], 30, "hub B sees it")
        outcome = send_command(api_b, VEHICLE, name="set_mode", mode="LOITER")
        assert outcome["status"] == "accepted", outcome
        # The flight controller changed mode: the agent on hub A obeyed.
        on_b.wait_until(
            lambda v: (v[VEHICLE].get("state") or {}).get("mode") == "LOITER", 20, "LOITER"
        )
        # Audited and logged in the shared database, as any command.
        commands = api_b.get("/api/v1/commands", params={"vehicle_id": VEHICLE}).json()
    assert any(c["name"] == "set_mode" and c["status"] == "accepted" for c in commands["commands"])
    # Hub A passed it on: the agent never left A for B.
    hub_a_log = (hubs.fleet.log_dir / "hub.log").read_text()
    assert f"{VEHICLE} set_mode (for another hub) -> " in hub_a_log
    assert "agent sim_1 connected" not in (hubs.fleet.log_dir / "hub_b.log").read_text()


def test_a_dashboard_on_hub_b_sees_telemetry_from_an_agent_on_hub_a(hubs: TwoHubs) -> None:
    token_from_a = hubs.admin_token(hubs.a)
    with FleetWatcher(hubs.a, token_from_a) as on_a:
        on_a.wait_until(connected(VEHICLE), 60, f"{VEHICLE} on hub A")
    # A token issued by hub A opens hub B's feed too: tokens live in the shared database.
    with FleetWatcher(hubs.b, token_from_a) as on_b:

        def fresh(vehicles: dict[str, dict[str, Any]]) -> bool:
            state = (vehicles.get(VEHICLE) or {}).get("state") or {}
            return state.get("lat") is not None and (vehicles[VEHICLE].get("last_seen") or 0) > (
                time.time() - 2
            )

        on_b.wait_until(fresh, 30, "live telemetry of hub A's vehicle on hub B")
        first = on_b.vehicles[VEHICLE]["last_seen"]
        on_b.wait_until(lambda v: v[VEHICLE]["last_seen"] > first, 10, "the next update")


def test_killing_hub_a_moves_its_agent_to_hub_b_with_no_telemetry_lost(hubs: TwoHubs) -> None:
    with FleetWatcher(hubs.a, hubs.admin_token(hubs.a)) as on_a:
        on_a.wait_until(connected(VEHICLE), 60, f"{VEHICLE} on hub A")
    # A second or two of telemetry stored through A, then A dies: no flush, no goodbye.
    poll_until(
        lambda: sum(len(s) for s in stored_seqs(hubs.database_url, VEHICLE).values()) >= 20,
        30,
        "telemetry stored through hub A",
    )
    hubs.fleet.kill("hub")
    killed_at = time.time()
    with FleetWatcher(hubs.b, hubs.admin_token(hubs.b)) as on_b:

        def fresh(vehicles: dict[str, dict[str, Any]]) -> bool:
            vehicle = vehicles.get(VEHICLE) or {}
            return bool(vehicle.get("connected")) and (vehicle.get("last_seen") or 0) > killed_at

        on_b.wait_until(fresh, 60, "the agent's telemetry through hub B")
        with api_client(hubs.b, hubs.admin_token(hubs.b)) as api_b:
            # Hub B holds the agent now: a command reaches it without routing.
            outcome = send_command(api_b, VEHICLE, name="set_mode", mode="LOITER")
            assert outcome["status"] == "accepted", outcome
    # Telemetry goes on through B (waited for: how much arrives by the time the command
    # has gone through depends on how fast the failover was).
    poll_until(
        lambda: sum(len(s) for s in stored_seqs(hubs.database_url, VEHICLE).values()) > 30,
        30,
        "telemetry stored through hub B",
    )
    # The agent stops for its last samples to be acknowledged before the count.
    hubs.fleet.stop()
    [seqs] = stored_seqs(hubs.database_url, VEHICLE).values()
    assert seqs[0] == 0
    assert seqs == list(range(len(seqs))), "a gap or a duplicate in the stored telemetry"
    assert len(seqs) > 30


def _ready_for_a_pilot(hubs: TwoHubs) -> None:
    """The vehicle on hub A, with a GPS fix, taking the agent's stick input; a pilot
    (an operator) known to both hubs."""
    admin_a = hubs.admin_token(hubs.a)
    with FleetWatcher(hubs.a, admin_a) as on_a, api_client(hubs.a, admin_a) as api_a:
        on_a.wait_until(connected(VEHICLE), 60, f"{VEHICLE} on hub A")
        on_a.wait_until(
            lambda v: (v[VEHICLE].get("state") or {}).get("gps_fix", 0) >= 3, 60, "a GPS fix"
        )
        # The agent opens browser control only where the autopilot takes its input: the
        # launcher set SYSID_MYGCS to the agent's id, as `gcs demo` does.
        created = api_a.post(
            "/api/v1/users",
            json={"username": "pilot", "password": OPERATOR_PASSWORD, "role": "operator"},
        )
        assert created.status_code in (200, 201), created.text


def test_a_lease_taken_on_hub_a_is_honoured_on_hub_b(hubs: TwoHubs) -> None:
    _ready_for_a_pilot(hubs)
    pilot_on_a = Dashboard(hubs.a, access_token(hubs.a, "pilot", OPERATOR_PASSWORD))
    admin_on_b = Dashboard(hubs.b, hubs.admin_token(hubs.b))
    try:
        granted = pilot_on_a.control("acquire")
        assert (granted["type"], granted["holder"]) == ("lease", "pilot"), granted
        # A second operator, on the other hub, is refused while the pilot flies...
        refused = admin_on_b.control("acquire")
        assert refused["type"] == "lease_refused", refused
        assert f"{VEHICLE} is flown by hand by pilot" in refused["reason"]
        # ...and the pilot's commands through hub B go through to the vehicle on hub A.
        pilot_b = access_token(hubs.b, "pilot", OPERATOR_PASSWORD)
        with api_client(hubs.b, pilot_b) as api_b:
            outcome = send_command(api_b, VEHICLE, name="set_mode", mode="LOITER")
        assert outcome["status"] == "accepted", outcome
        # Given up on A, the lease is free on B at once.
        pilot_on_a.control("release")
        taken = admin_on_b.control("acquire")
        assert (taken["type"], taken["holder"]) == ("lease", "admin"), taken
    finally:
        pilot_on_a.close()
        admin_on_b.close()


def test_a_pilot_on_hub_b_flies_the_vehicle_on_hub_a(hubs: TwoHubs) -> None:
    """The lease and the stick frames go through hub B, the agent is on hub A. The
    agent's deadman (0.5 s without a frame: hold) is the witness: it stays quiet while
    the frames cross from B to A, and speaks once they stop; the lease on B ends with it."""
    _ready_for_a_pilot(hubs)
    pilot = Dashboard(hubs.b, access_token(hubs.b, "pilot", OPERATOR_PASSWORD))
    try:
        granted = pilot.control("acquire")
        assert (granted["type"], granted["holder"]) == ("lease", "pilot"), granted
        period = 1.0 / 25
        until = time.monotonic() + 5.0  # past the agent's 3 s grace for the first frame
        seq = 0
        while time.monotonic() < until:
            seq += 1
            pilot.stick(seq)
            time.sleep(period)  # the pilot's 25 Hz: the test's input, not a wait
        assert not pilot.events("manual input stopped"), "frames did not reach the agent"
        poll_until(lambda: pilot.events("manual input stopped"), 10, "the deadman, on B")

        def ended() -> list[dict[str, Any]]:
            return [m for m in list(pilot.received) if m["type"] == "lease" and not m["holder"]]

        # Ended by the agent's word from hub A (not by the lease's own expiry on B).
        [end] = poll_until(ended, 10, "the lease on hub B to end with browser control")
        assert "manual input stopped" in end["reason"], end
    finally:
        pilot.close()


def test_a_vehicle_whose_hub_died_is_shown_offline_until_its_agent_comes_back(
    hubs: TwoHubs,
) -> None:
    """Hub A dies while its agent is frozen (SIGSTOP: it cannot reconnect yet): hub B
    stops showing the vehicle connected once no hub answers for it, and shows it
    connected again when the agent, thawed, reconnects to B."""
    with FleetWatcher(hubs.a, hubs.admin_token(hubs.a)) as on_a:
        on_a.wait_until(connected(VEHICLE), 60, f"{VEHICLE} on hub A")
    [agent] = [m.process for m in hubs.fleet.processes if m.name == "agent_1"]
    with FleetWatcher(hubs.b, hubs.admin_token(hubs.b)) as on_b:
        on_b.wait_until(lambda v: VEHICLE in v and v[VEHICLE]["connected"], 30, "hub B sees it")
        agent.send_signal(signal.SIGSTOP)
        try:
            hubs.fleet.kill("hub")
            on_b.wait_until(lambda v: not v[VEHICLE]["connected"], 20, "shown offline on B")
        finally:
            agent.send_signal(signal.SIGCONT)
        on_b.wait_until(lambda v: v[VEHICLE]["connected"], 60, "back, through hub B")


def _survey_over_home(hubs: TwoHubs) -> dict[str, Any]:
    """A small survey south-east of the vehicle's home, for it alone."""
    lat, lon, _ = hubs.fleet.plan.vehicle_home(0)
    frame = LocalFrame(lat, lon)
    corners = [(30.0, 30.0), (90.0, 30.0), (90.0, 80.0), (30.0, 80.0), (30.0, 30.0)]
    ring = [list(reversed(frame.to_geo(east, north))) for east, north in corners]
    return {
        "area": {"type": "Polygon", "coordinates": [ring]},
        "camera": "sony_a6000_16mm",
        "altitude_m": 30,
        "side_overlap_pct": 60,
        "front_overlap_pct": 70,
        "angle_deg": 0,
        "speed_ms": 8,
        "vehicle_ids": [VEHICLE],
    }


@pytest.mark.slow
def test_one_hub_drives_a_survey_and_another_takes_it_over_when_it_dies(hubs: TwoHubs) -> None:
    admin_a = hubs.admin_token(hubs.a)
    with FleetWatcher(hubs.a, admin_a) as on_a, api_client(hubs.a, admin_a) as api_a:
        on_a.wait_until(on_the_ground(VEHICLE), 90, f"{VEHICLE} ready on hub A")
        created = api_a.post("/api/v1/surveys", json=_survey_over_home(hubs))
        assert created.status_code == 201, created.text
    survey_id = created.json()["survey"]["id"]
    # Hub B restarts: it finds the survey among the active ones in the shared store.
    hubs.fleet.kill("hub_b")
    hubs.start_b()
    with api_client(hubs.b, hubs.admin_token(hubs.b)) as api_b:
        # Hub B reads it, but hub A drives it: B does not act on it.
        progress = api_b.get(f"/api/v1/surveys/{survey_id}/progress")
        assert progress.status_code == 200, progress.text
        assert progress.json()["state"] == "planned"
        refused = api_b.post(f"/api/v1/surveys/{survey_id}/abort")
        assert refused.status_code == 404, refused.text

        hubs.fleet.kill("hub")

        # Once hub A's claim has lapsed, hub B takes the survey over from its stored state.
        def aborted_on_b() -> bool:
            answer = api_b.post(f"/api/v1/surveys/{survey_id}/abort")
            return answer.status_code == 200

        poll_until(aborted_on_b, 60, "hub B to take the survey over", every_s=1.0)
        after = api_b.get(f"/api/v1/surveys/{survey_id}/progress").json()
    assert after["state"] == "aborted"
