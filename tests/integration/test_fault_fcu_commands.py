"""Commands when the flight controller cannot answer: its link dropped (and restored), or a
flight controller that keeps its heartbeat but stops answering commands. Each command
fails with a reason that says which, and what reaches the flight controller is MAVLink's
command protocol and no more: a bounded number of COMMAND_LONGs per command, each retry
with its confirmation counter one higher, nothing after the answer, nothing queued up
while the link was down and sent when it came back.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import httpx
import pytest
from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from tests.support.api import api_client
from tests.support.fcu import FcuTap, sim_config, state_of
from tests.support.processes import agent_process
from tests.support.silent_fcu import SilentFlightController
from tests.support.simulators import serving
from tests.support.watcher import FleetWatcher, connected
from vehicle_agents.fcu.commands import CommandTimeouts

pytestmark = pytest.mark.integration

LAND = mavlink2.MAV_CMD_NAV_LAND
ATTEMPTS = CommandTimeouts().attempts
ACK_S = CommandTimeouts().ack_s
REQUESTS = 3


def _land(api: httpx.Client, vehicle: str) -> httpx.Response:
    # Landing is never held back by the hub's rails: it really goes to the vehicle.
    return api.post(f"/api/v1/vehicles/{vehicle}/commands", json={"name": "land"})


def test_a_flight_controller_that_stops_answering_gets_bounded_retries_not_a_storm(
    hub: str, admin_token: str, enrol: Callable[[str], str]
) -> None:
    with (
        SilentFlightController(system_id=7) as fcu,
        agent_process(hub, enrol("mute"), "mute", fcu.port) as agent,
    ):
        with FleetWatcher(hub, admin_token) as watcher:
            watcher.wait_until(connected("mute"), 30, "the vehicle to connect")
        # Operators press again when nothing happens: several requests at once.
        with (
            api_client(hub, admin_token, timeout_s=60) as api,
            ThreadPoolExecutor(REQUESTS) as pool,
        ):
            answers = list(pool.map(lambda _: _land(api, "mute"), range(REQUESTS)))
        for answer in answers:
            assert answer.status_code == 504, answer.text
            assert "MAV_CMD_NAV_LAND" in answer.json()["detail"]
            assert (
                f"no COMMAND_ACK from the flight controller after {ATTEMPTS} attempts"
                in (answer.json()["detail"])
            )
        # Nothing more arrives once the commands have been answered.
        time.sleep(2 * ACK_S)  # the time a late retry would take to show, not a sync
        sent = fcu.commands(LAND)
        assert len(sent) == REQUESTS * ATTEMPTS, [m.confirmation for m in sent]
        assert sorted(m.confirmation for m in sent) == sorted(list(range(ATTEMPTS)) * REQUESTS), (
            "each retry carries the next confirmation number"
        )
        assert agent.poll() is None


def test_commands_while_the_flight_controller_link_is_down_fail_at_once_and_are_not_replayed(
    hub: str, admin_token: str, enrol: Callable[[str], str], tmp_path: Path
) -> None:
    vehicle = "unplugged"
    state = state_of(vehicle)
    with (
        serving(sim_config()) as (_server, address),
        FcuTap(address.port) as tap,
        agent_process(hub, enrol(vehicle), vehicle, tap.port, log_dir=tmp_path),
        FleetWatcher(hub, admin_token) as watcher,
        api_client(hub, admin_token, timeout_s=60) as api,
    ):
        watcher.wait_until(lambda v: state(v).get("fcu_connected") is True, 30, "the FCU link")

        def lands_sent() -> int:
            with tap._changed:
                return sum(
                    1
                    for m in tap._from_agent
                    if m.get_type() == "COMMAND_LONG" and m.command == LAND
                )

        tap.cut()  # the cable is pulled
        watcher.wait_until(lambda v: state(v).get("fcu_connected") is False, 15, "link lost")
        for _ in range(REQUESTS):
            asked = time.monotonic()
            answer = _land(api, vehicle)
            assert time.monotonic() - asked < ACK_S, "refused at once, not after retries"
            assert answer.status_code == 200, answer.text  # the agent's answer, delivered
            outcome = answer.json()["outcome"]
            assert outcome["status"] == "failed", outcome
            assert outcome["message"] == "flight controller link is down"
        tap.start()  # plugged back in
        watcher.wait_until(lambda v: state(v).get("fcu_connected") is True, 20, "link back")
        time.sleep(2 * ACK_S)  # time for a queued command to show up, not a sync
        assert lands_sent() == 0, "a command refused while the link was down went out later"
        # And the link is usable again: one command, one COMMAND_LONG, one answer.
        answer = _land(api, vehicle)
        assert answer.status_code == 200, answer.text
        assert answer.json()["outcome"]["status"] == "accepted"
        assert lands_sent() == 1
