"""One call, one command, many vehicles: concurrent, checked one by one, a result each."""

from __future__ import annotations

import json
import threading
from collections.abc import Callable
from contextlib import ExitStack

import httpx
from websockets.sync.client import ClientConnection

from protocol.messages import CommandOutcome, CommandResult, encode
from tests.support.accounts import _report_position
from tests.support.agents import scripted_agent


def _answer_commands(agent: ClientConnection, answered: list[str]) -> threading.Thread:
    """Accept every command until the connection closes, noting each one."""

    def run() -> None:
        try:
            while True:
                request = json.loads(agent.recv())
                answered.append(request["command"]["name"])
                outcome = CommandOutcome(
                    status="accepted", result="MAV_RESULT_ACCEPTED", message="ok"
                )
                agent.send(encode(CommandResult(request_id=request["request_id"], outcome=outcome)))
        except Exception:  # the test closed the connection
            return

    thread = threading.Thread(target=run, daemon=True)
    thread.start()
    return thread


def test_group_command_reaches_each_selected_vehicle(
    hub: str, admin_api: httpx.Client, enrol: Callable[[str], str]
) -> None:
    answered: dict[str, list[str]] = {vehicle: [] for vehicle in ("g1", "g2", "g3")}
    with ExitStack() as stack:
        for vehicle, log in answered.items():
            agent = stack.enter_context(scripted_agent(hub, vehicle, enrol(vehicle)))
            _report_position(agent)
            _answer_commands(agent, log)

        selection = {"vehicle_ids": ["g1", "g2"], "command": {"name": "land"}}
        response = admin_api.post("/api/v1/fleet/commands", json=selection)
        assert response.status_code == 200, response.text
        results = {r["vehicle_id"]: r for r in response.json()["results"]}
        assert results["g1"]["status_code"] == results["g2"]["status_code"] == 200
        assert results["g1"]["outcome"]["status"] == "accepted"
        assert answered == {"g1": ["land"], "g2": ["land"], "g3": []}

        # The whole fleet, with a command that breaks a rail: each vehicle says why.
        too_high = {"command": {"name": "takeoff", "altitude": 400}}
        everyone = admin_api.post("/api/v1/fleet/commands", json=too_high).json()["results"]
        assert sorted(r["vehicle_id"] for r in everyone) == ["g1", "g2", "g3"]
        assert {r["status_code"] for r in everyone} == {422}
        assert all(r["violations"][0]["rule"] == "max_altitude" for r in everyone)
        assert answered["g3"] == []  # nothing reached a vehicle

    audit = admin_api.get("/api/v1/audit", params={"action": "command"}).json()["entries"]
    assert {entry["target"] for entry in audit} >= {"g1", "g2", "g3"}
