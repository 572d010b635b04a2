"""A user name with a newline cannot forge a line in the hub's log, nor a peer's text one in
the agent's."""

from __future__ import annotations

import json
from pathlib import Path

import httpx

from gcs.launcher import FleetPlan, LocalFleet, free_port
from tests.support.hubs import TEST_HUB_ENV
from tests.support.mavlink_peer import ScriptedFlightController
from tests.support.processes import agent_process
from tests.support.scripted_hub import ScriptedHub, _command

FORGED = "2031-01-01 00:00:00,000 INFO    backend.audit: audit: admin"


def test_a_user_name_cannot_forge_a_log_line(tmp_path: Path) -> None:
    plan = FleetPlan(vehicles=0, port=free_port(), data_dir=tmp_path)
    with LocalFleet(plan) as fleet:
        # The real `gcs hub` process, with the logging its command line sets up.
        fleet.start(hub_env={**TEST_HUB_ENV, "GCS_AGENT_TOKENS": "v1=" + "t" * 32})
        fleet.wait_until_ready()
        # A denied login: the audit logger logs the user name it was given.
        denied = httpx.post(
            f"{plan.hub_http}/api/v1/auth/login",
            json={"username": "x\n" + FORGED, "password": "wrong"},
            timeout=30,
        )
        assert denied.status_code == 401
    log = (fleet.log_dir / "hub.log").read_text()
    lines = log.splitlines()
    assert not [line for line in lines if line.startswith("2031")], log[-2000:]
    assert any("login x\\n" + FORGED in line for line in lines), log[-2000:]


AGENT_FORGED = "2031-01-01 00:00:00,000 ERROR   vehicle_agents.agent: flight controller lost"


def test_what_the_hub_says_cannot_forge_a_line_in_the_agents_log(tmp_path: Path) -> None:
    """The agent logs texts that come from its peers (the hub's error replies, a command's
    reasons from the flight controller's STATUSTEXTs): escaped there too."""
    with (
        ScriptedFlightController() as fcu,
        ScriptedHub() as hub,
        agent_process(hub.url, "t" * 32, "logs_1", fcu.port, tmp_path),
    ):
        connection = hub.connections.get(timeout=30)
        reply = {"type": "error", "code": "bad_frame", "message": "x\n" + AGENT_FORGED}
        connection.send(json.dumps(reply))
        # answered after the reply was read (and so logged): the log is written by then
        assert hub.answer_to(connection, _command("after", 12))["status"] == "failed"
    log = (tmp_path / "logs_1.log").read_text()
    lines = log.splitlines()
    assert not [line for line in lines if line.startswith("2031")], log[-2000:]
    assert any("x\\n" + AGENT_FORGED in line for line in lines), log[-2000:]
