"""A poor field link, made real: the vehicle (simulator and agent) sits in its own network
namespace and reaches the hub over a veth pair shaped by `tc netem` both ways (300 ms
delay with 50 ms jitter, 5 % loss, 1 % reordering, 256 kbit/s). Telemetry must still be
stored whole, commands must still get their answers within the hub's deadline, and the
dashboard's view must fall behind by rate (fewer updates), never by a delay that grows.
"""

from __future__ import annotations

import json
import os
import sqlite3
import statistics
import subprocess
import sys
import time
from collections.abc import Iterator
from contextlib import ExitStack
from dataclasses import dataclass
from pathlib import Path

import pytest
from websockets.sync.client import connect

from gcs.launcher import FleetPlan, LocalFleet, end_with_parent, free_port
from protocol.messages import CLIENT_WS_PATH
from tests.support.api import access_token, api_client, send_command
from tests.support.hubs import TEST_HUB_ENV
from tests.support.netem import FieldLink, ImpairedRelay, field_link
from tests.support.waiting import poll_until

pytestmark = [pytest.mark.integration, pytest.mark.slow]

VEHICLE = "field_1"
RATE_HZ = 10.0
FLY_S = 40.0
COMMAND_DEADLINE_S = 15.0  # the hub's command_timeout_s


@dataclass
class FieldFleet:
    fleet: LocalFleet
    link: FieldLink
    agent: subprocess.Popen[bytes]
    started: float


@pytest.fixture
def field_fleet(tmp_path: Path) -> Iterator[FieldFleet]:
    with ExitStack() as stack:
        link = stack.enter_context(field_link())
        plan = FleetPlan(vehicles=0, port=free_port(), data_dir=tmp_path)
        fleet = stack.enter_context(LocalFleet(plan))
        fleet.start(TEST_HUB_ENV)
        fleet.wait_until_ready()
        admin = access_token(plan.hub_http, "admin", plan.admin_password)
        with api_client(plan.hub_http, admin) as api:
            enrolled = api.post(f"/api/v1/vehicles/{VEHICLE}/agent-tokens")
            assert enrolled.status_code == 201, enrolled.text
            token = enrolled.json()["token"]
        # The vehicle reaches the hub across the pair only; the test's own clients use
        # loopback, so only the vehicle's link is poor.
        relay = ImpairedRelay(link.host_address, ("127.0.0.1", plan.port), not link.netem)
        relay.start()
        stack.callback(relay.cut)
        logs = fleet.log_dir
        sim_port = free_port()  # the namespace is empty: any port is free in it

        def inside(name: str, argv: list[str], env: dict[str, str]) -> subprocess.Popen[bytes]:
            log = stack.enter_context((logs / f"{name}.log").open("wb"))
            process = subprocess.Popen(
                link.command([sys.executable, "-m", "gcs", *argv]),
                stdout=log,
                stderr=subprocess.STDOUT,
                env={**env},
                preexec_fn=end_with_parent(),
            )
            stack.callback(process.wait, 10)
            stack.callback(process.terminate)
            return process

        env = dict(os.environ)
        inside("sim", ["sim", "--listen", f"tcp:127.0.0.1:{sim_port}", "--speedup", "4"], env)
        agent = inside(
            "agent",
            [
                "agent",
                "--fcu",
                f"tcp:127.0.0.1:{sim_port}",
                "--hub",
                f"ws://{link.host_address}:{relay.port}",
                "--vehicle-id",
                VEHICLE,
                "--telemetry-rate-hz",
                str(RATE_HZ),
                "--outbox-dir",
                str(tmp_path / "onboard"),
            ],
            {**env, "GCS_AGENT_TOKEN": token},
        )
        yield FieldFleet(fleet, link, agent, time.time())


def _stored_seqs(fleet: LocalFleet) -> tuple[int, int, int]:
    """(rows, distinct sequence numbers, highest) of the vehicle's single agent run."""
    with sqlite3.connect(fleet.plan.data_dir / "gcs.sqlite3", timeout=10) as db:
        row = db.execute(
            "SELECT count(*), count(DISTINCT seq), coalesce(max(seq), -1) FROM telemetry "
            f"WHERE vehicle_id = '{VEHICLE}'"
        ).fetchone()
    return row[0], row[1], row[2]


def test_a_poor_field_link_keeps_telemetry_whole_commands_answered_and_delay_flat(
    field_fleet: FieldFleet,
) -> None:
    fleet = field_fleet.fleet
    base = fleet.plan.hub_http
    token = access_token(base, "admin", fleet.plan.admin_password)
    ws_url = base.replace("http://", "ws://") + CLIENT_WS_PATH
    # (arrival on the monotonic clock, delay behind the agent's stamp) per live update
    delays: list[tuple[float, float]] = []
    state: dict[str, object] = {}
    with (
        connect(
            ws_url, additional_headers={"Authorization": f"Bearer {token}"}, max_queue=None
        ) as feed,
        api_client(base, token, timeout_s=60) as api,
    ):

        def follow(until: float) -> None:
            """Read the dashboard's feed until ``until`` (monotonic)."""
            while (remaining := until - time.monotonic()) > 0:
                try:
                    frame = feed.recv(timeout=remaining)
                except TimeoutError:
                    return
                message = json.loads(frame)
                # the snapshot, then batches of the vehicles that changed
                vehicles = message["vehicles"] if message["type"] in ("fleet", "vehicles") else []
                for vehicle in vehicles:
                    if vehicle["id"] == VEHICLE and vehicle.get("state"):
                        state.update(vehicle["state"])
                        delays.append((time.monotonic(), time.time() - vehicle["last_seen"]))

        def wait_for(condition: object, timeout_s: float, what: str) -> None:
            deadline = time.monotonic() + timeout_s
            while not condition():  # type: ignore[operator]
                assert time.monotonic() < deadline, f"timed out waiting for {what}: {state}"
                follow(min(deadline, time.monotonic() + 0.5))

        wait_for(
            lambda: state.get("gps_fix", 0) >= 3 and state.get("home_lat") is not None,  # type: ignore[operator]
            120,
            "the vehicle to report over the field link",
        )
        # Commands get their answers (the flight controller's, through the poor link)
        # inside the hub's deadline, not a timeout.
        for command in (
            {"name": "set_mode", "mode": "GUIDED"},
            {"name": "arm"},
            {"name": "takeoff", "altitude": 20},
        ):
            asked = time.monotonic()
            outcome = send_command(api, VEHICLE, **command)
            assert outcome["status"] == "accepted", (command, outcome)
            assert time.monotonic() - asked < COMMAND_DEADLINE_S
        flying_from = len(delays)
        follow(time.monotonic() + FLY_S)
        flown = delays[flying_from:]

    # Delay: flat, not growing. The last third's median is no worse than the first
    # third's by more than the link's own jitter and a batching interval.
    third = len(flown) // 3
    assert third >= 10, f"only {len(flown)} live updates in {FLY_S:g} s"
    early = statistics.median(d for _, d in flown[:third])
    late = statistics.median(d for _, d in flown[-third:])
    assert late < early + 0.5, f"the live view falls further behind: {early:.2f} s -> {late:.2f} s"
    assert late < 3.0, f"the live view is {late:.2f} s behind"

    # Telemetry: every sample the agent took is stored, each once.
    produced = int((time.time() - field_fleet.started) * RATE_HZ * 0.8)
    poll_until(
        lambda: (stored := _stored_seqs(fleet))[2] >= produced and stored[1] == stored[2] + 1,
        90,
        f"at least {produced} samples stored without a hole",
    )
    rows, distinct, highest = _stored_seqs(fleet)
    assert rows == distinct == highest + 1, "a sample is missing or stored twice"
    assert field_fleet.agent.poll() is None
