"""Several hubs on a NATS server that requires a login (docs/deployer.md, "Several hubs",
docs/security.md): the shipped deploy/nats-server.conf run by the machine's nats-server.

A command that crosses to another hub names its sender; the hub that carries it out
checks that user in the shared database, and writes the audit row and the command log.
A message on a command subject naming no sender the database knows reaches no agent.
"""

from __future__ import annotations

import asyncio
import json
import os
import secrets
import socket
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import nats
import psycopg
import pytest

from gcs.launcher import free_port
from tests.support.api import api_client, send_command
from tests.support.nats_server import HUB_USER, login_refused, nats_server
from tests.support.two_hubs import VEHICLE, TwoHubs, two_hubs
from tests.support.waiting import poll_until
from tests.support.watcher import FleetWatcher, connected

pytestmark = pytest.mark.integration


class SecuredHubs:
    def __init__(self, hubs: TwoHubs, address: str, password: str) -> None:
        self.hubs = hubs
        self.address = address
        self.password = password


@pytest.fixture
def secured(tmp_path: Path) -> Iterator[SecuredHubs]:
    # Starts as a number would: the shipped config must still read it as a string.
    password = "12e3" + secrets.token_hex(16)
    with nats_server(password, log_path=tmp_path / "nats.log") as address:
        # Hub A presents the login as settings, hub B inside its URL: both forms work.
        bus_a = {
            "GCS_BUS_URL": f"nats://{address}",
            "GCS_BUS_USER": HUB_USER,
            "GCS_BUS_PASSWORD": password,
        }
        bus_b = {"GCS_BUS_URL": f"nats://{HUB_USER}:{password}@{address}"}
        with two_hubs(tmp_path, bus_a, bus_b) as hubs:
            yield SecuredHubs(hubs, address, password)


def _rows(database_url: str, query: str, *args: object) -> list[tuple[Any, ...]]:
    with psycopg.connect(database_url.replace("postgresql+psycopg://", "postgresql://")) as db:
        return db.execute(query, args).fetchall()


def _hub_pid(hubs: TwoHubs, name: str) -> int:
    [process] = [p.process for p in hubs.fleet.processes if p.name == name]
    return process.pid


def test_a_client_without_the_login_is_refused_by_the_bus(secured: SecuredHubs) -> None:
    assert "Authorization Violation" in (login_refused(secured.address) or "")
    wrong = login_refused(secured.address, user=HUB_USER, password="guessed-password")
    assert "Authorization Violation" in (wrong or "")


def test_a_command_through_hub_b_is_carried_out_and_recorded_by_hub_a(
    secured: SecuredHubs,
) -> None:
    hubs = secured.hubs
    with FleetWatcher(hubs.a, hubs.admin_token(hubs.a)) as on_a:
        on_a.wait_until(connected(VEHICLE), 60, f"{VEHICLE} on hub A")
    with (
        FleetWatcher(hubs.b, hubs.admin_token(hubs.b)) as on_b,
        api_client(hubs.b, hubs.admin_token(hubs.b)) as api_b,
    ):
        on_b.wait_until(lambda v: VEHICLE in v and v[VEHICLE]["connected"], 30, "hub B sees it")
        outcome = send_command(api_b, VEHICLE, name="set_mode", mode="LOITER")
        assert outcome["status"] == "accepted", outcome

    audit = poll_until(
        lambda: _rows(
            hubs.database_url,
            "SELECT actor, role, token_kind, token_id, outcome, detail FROM audit_log "
            "WHERE action = 'command' AND target = %s",
            VEHICLE,
        ),
        20,
        "the command's audit row",
    )
    # One row, written by hub A (which carried it out), naming the user and the token
    # they used on hub B; hub B, which only asked, did not write a second.
    [(actor, role, token_kind, token_id, result, detail)] = audit
    assert (actor, role, token_kind, result) == ("admin", "admin", "access", "ok")
    assert token_id is not None
    routed_from = json.loads(detail)["routed_from"]
    assert routed_from.startswith(f"{socket.gethostname()[:48]}-{_hub_pid(hubs, 'hub_b')}-")
    commands = poll_until(
        lambda: _rows(
            hubs.database_url,
            "SELECT actor, name, status FROM commands WHERE vehicle_id = %s",
            VEHICLE,
        ),
        20,
        "the command log entry",
    )
    assert commands == [("admin", "set_mode", "accepted")]
    hub_a_log = (hubs.fleet.log_dir / "hub.log").read_text()
    assert f"{VEHICLE} set_mode (for another hub) -> " in hub_a_log
    assert "(by admin)" in hub_a_log
    # The login never reaches a log: hub B's URL is shown redacted.
    for name in ("hub.log", "hub_b.log"):
        assert secured.password not in (hubs.fleet.log_dir / name).read_text()
    assert (
        f"nats://{HUB_USER}:***@{secured.address}" in (hubs.fleet.log_dir / "hub_b.log").read_text()
    )


async def _raw_requests(address: str, password: str, subject: str) -> list[dict[str, Any]]:
    """What a client with the bus's login (a compromised host, say) gets for commands
    that name no sender, a forged one, and a real user's name with a made-up token."""
    disarm = {"name": "disarm", "force": True}
    forged = {"name": "admin", "role": "admin", "token_id": 987654, "token_kind": "session"}
    payloads = [
        {"command": disarm, "timeout_s": 5},
        {"command": disarm, "timeout_s": 5, "sender": forged},
        {"command": disarm, "timeout_s": 5, "sender": {**forged, "token_id": 1}},
    ]
    connection = await nats.connect(f"nats://{HUB_USER}:{password}@{address}")
    try:
        answers = []
        for payload in payloads:
            reply = await connection.request(subject, json.dumps(payload).encode(), timeout=10)
            answers.append(json.loads(reply.data))
        return answers
    finally:
        await connection.close()


def test_a_command_on_the_bus_without_a_known_sender_reaches_no_agent(
    secured: SecuredHubs,
) -> None:
    hubs = secured.hubs
    admin = hubs.admin_token(hubs.a)
    with FleetWatcher(hubs.a, admin) as on_a:
        on_a.wait_until(connected(VEHICLE), 60, f"{VEHICLE} on hub A")
    subject = f"{hubs.bus_prefix}.agent.{VEHICLE}.command"
    answers = asyncio.run(_raw_requests(secured.address, secured.password, subject))
    # Token 1 exists (a session of the admin's, say) but is not an admin's "session"
    # as named, or is a different kind: the database's word, not the message's, counts.
    for answer in answers:
        assert answer["error"] == "refused", answer
        assert answer["outcome"] is None
        assert answer["recorded"] is False
    # Refused before the agent: no command reached it, so none is logged or audited...
    assert _rows(hubs.database_url, "SELECT id FROM commands WHERE vehicle_id = %s", VEHICLE) == []
    hub_a_log = (hubs.fleet.log_dir / "hub.log").read_text()
    assert "(for another hub)" not in hub_a_log
    # ...and each refusal is logged and counted.
    assert hub_a_log.count(f"routed command for {VEHICLE} refused") == 3
    with api_client(hubs.a, admin) as api_a:
        metrics = api_a.get("/metrics").text
    assert 'gcs_rejected_frames_total{surface="bus_command"} 3.0' in metrics


def test_outside_development_a_hub_refuses_a_bus_url_without_credentials(
    tmp_path: Path,
) -> None:
    env = {
        key: value
        for key, value in os.environ.items()
        if not key.startswith("GCS_") and key != "DATABASE_URL"
    }
    env.update(
        GCS_ENVIRONMENT="production",
        GCS_ADMIN_PASSWORD=secrets.token_hex(12),
        GCS_BUS_URL="nats://127.0.0.1:4222",
    )
    result = subprocess.run(
        [sys.executable, "-m", "gcs", "hub", "--port", str(free_port())],
        cwd=tmp_path,
        env=env,
        capture_output=True,
        text=True,
        timeout=60,
        check=False,
    )
    assert result.returncode == 2, result.stderr
    assert "GCS_BUS_URL nats://127.0.0.1:4222 carries no credentials" in result.stderr
    assert "GCS_BUS_USER and GCS_BUS_PASSWORD" in result.stderr
