"""A user name with a newline cannot forge a line in the hub's log."""

from __future__ import annotations

from pathlib import Path

import httpx

from gcs.launcher import FleetPlan, LocalFleet, free_port

FORGED = "2031-01-01 00:00:00,000 INFO    backend.audit: audit: admin"


def test_a_user_name_cannot_forge_a_log_line(tmp_path: Path) -> None:
    plan = FleetPlan(vehicles=0, port=free_port(), data_dir=tmp_path)
    with LocalFleet(plan) as fleet:
        # The real `gcs hub` process, with the logging its command line sets up.
        fleet.start(hub_env={"GCS_AGENT_TOKENS": "v1=" + "t" * 32})
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
