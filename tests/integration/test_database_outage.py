"""A database outage must not block the commands that get a vehicle out of trouble:
principals resolve from a short-lived cache, and audit and command-log rows wait in a
local spool until the database is back, none lost."""

from __future__ import annotations

import time
from collections.abc import Iterator
from contextlib import ExitStack, contextmanager
from pathlib import Path
from typing import Any

import pytest

from tests.conftest import ADMIN_PASSWORD, POSTGRES_ADDRESS, hub_settings, scratch_postgres
from tests.support.accounts import PASSWORD, _no_command_reaches, _user
from tests.support.agents import scripted_agent
from tests.support.api import access_token, api_client
from tests.support.databases import answering
from tests.support.hub_server import running_hub
from tests.support.tcp_proxy import CuttableProxy
from tests.support.waiting import poll_until

# The server the suite uses (GCS_TEST_POSTGRES_ADDRESS may name another), behind the proxy.
_host, _, _port = POSTGRES_ADDRESS.rpartition(":")
POSTGRES = (_host, int(_port))

SAFETY_COMMANDS = ("land", "rtl", "hold")


@contextmanager
def hub_behind(proxy: CuttableProxy, tmp_path: Path) -> Iterator[str]:
    with scratch_postgres() as url:
        proxied = url.replace(POSTGRES_ADDRESS, f"127.0.0.1:{proxy.port}")
        with running_hub(hub_settings(tmp_path, database_url=proxied, spool_retry_s=0.2)) as base:
            yield base


def test_land_rtl_and_hold_go_through_a_database_outage_and_nothing_is_lost(
    tmp_path: Path,
) -> None:
    with (
        CuttableProxy(POSTGRES) as proxy,
        hub_behind(proxy, tmp_path) as base,
        ExitStack() as clients,
    ):
        admin = clients.enter_context(api_client(base, access_token(base, "admin", ADMIN_PASSWORD)))
        agent_token = admin.post("/api/v1/vehicles/v1/agent-tokens").json()["token"]
        operator_token = access_token(base, _user(admin, "olivia", "operator"), PASSWORD)
        operator = clients.enter_context(api_client(base, operator_token))
        integration_token = admin.post("/api/v1/auth/api-tokens", json={"name": "ci"}).json()
        integration = clients.enter_context(api_client(base, integration_token["token"]))
        with scripted_agent(base, "v1", agent_token) as agent:
            # Each token has been resolved once before the outage.
            for client in (admin, operator, integration):
                assert client.get("/api/v1/vehicles").status_code == 200
            revoked = admin.delete(f"/api/v1/auth/api-tokens/{integration_token['id']}")
            assert revoked.status_code == 204

            outage_began = time.time()
            proxy.cut()
            for name in SAFETY_COMMANDS:
                with answering(agent) as received:
                    response = operator.post("/api/v1/vehicles/v1/commands", json={"name": name})
                    assert response.status_code == 200, response.text
                    assert response.json()["outcome"]["status"] == "accepted"
                assert [command["name"] for command in received] == [name]

            # A command the rails govern cannot be checked, so it is refused, not sent.
            takeoff = operator.post(
                "/api/v1/vehicles/v1/commands", json={"name": "takeoff", "altitude": 10}
            )
            assert takeoff.status_code == 503
            _no_command_reaches(agent)
            # The revocation cleared the cache: the revoked token is not served from it.
            assert integration.get("/api/v1/vehicles").status_code == 503
            spooled = operator.get("/api/v1/health").json()["rows_spooled"]
            # Three commands (an audit row and a command-log row each) and the refusal.
            assert spooled == 2 * len(SAFETY_COMMANDS) + 1
            outage_ended = time.time()
            proxy.start()

            poll_until(
                lambda: operator.get("/api/v1/health").json()["rows_spooled"] == 0,
                30,
                "the spooled rows to be stored",
            )
            audit = admin.get("/api/v1/audit", params={"actor": "olivia", "action": "command"})
            entries = audit.json()["entries"]
            log = operator.get("/api/v1/commands", params={"vehicle_id": "v1"}).json()
        assert [(e["detail"]["command"]["name"], e["outcome"]) for e in reversed(entries)] == [
            *((name, "ok") for name in SAFETY_COMMANDS),
            ("takeoff", "refused"),
        ]
        assert "database is unavailable" in entries[0]["detail"]["error"]
        # Stored with the time they happened, not the time the database came back.
        assert all(outage_began <= e["time"] <= outage_ended for e in entries)
        assert [(c["name"], c["status"]) for c in reversed(log["commands"])] == [
            (name, "accepted") for name in SAFETY_COMMANDS
        ]


@pytest.mark.parametrize("spool_dir", [None, "spool"], ids=["in-the-data-folder", "spool-dir"])
def test_a_spool_left_by_a_hub_that_stopped_mid_outage_is_stored_at_the_next_start(
    tmp_path: Path, spool_dir: str | None
) -> None:
    """...in the data folder, or in GCS_SPOOL_DIR (hubs that share a data folder), which
    the hub creates."""
    spool = {"spool_dir": tmp_path / spool_dir} if spool_dir else {}
    with CuttableProxy(POSTGRES) as proxy, scratch_postgres() as url:
        proxied = url.replace(POSTGRES_ADDRESS, f"127.0.0.1:{proxy.port}")
        settings = hub_settings(tmp_path, database_url=proxied, spool_retry_s=0.2, **spool)
        with running_hub(settings) as base:
            admin = api_client(base, access_token(base, "admin", ADMIN_PASSWORD))
            with admin:
                assert admin.get("/api/v1/vehicles").status_code == 200
                proxy.cut()
                # Refused for lack of a vehicle, audited as an attempt: into the spool.
                denied = admin.post("/api/v1/vehicles/v9/commands", json={"name": "land"})
                assert denied.status_code == 404
                assert admin.get("/api/v1/health").json()["rows_spooled"] == 1
        assert (tmp_path / (spool_dir or ".") / "spool.jsonl").stat().st_mode & 0o777 == 0o600
        if spool_dir:
            assert not (tmp_path / "spool.jsonl").exists()
        proxy.start()
        with running_hub(hub_settings(tmp_path, database_url=proxied, **spool)) as base:
            admin = api_client(base, access_token(base, "admin", ADMIN_PASSWORD))
            with admin:

                def stored() -> list[dict[str, Any]]:
                    page = admin.get("/api/v1/audit", params={"target": "v9"}).json()
                    entries: list[dict[str, Any]] = page["entries"]
                    return entries

                poll_until(stored, 30, "the earlier run's spooled row to be stored")
                (entry,) = stored()
                assert (entry["actor"], entry["outcome"]) == ("admin", "refused")
                assert admin.get("/api/v1/health").json()["rows_spooled"] == 0


def test_the_cache_keeps_a_token_for_its_lifetime_only(tmp_path: Path) -> None:
    """A cached principal never outlives its token, even with the database down."""
    with CuttableProxy(POSTGRES) as proxy, scratch_postgres() as url:
        proxied = url.replace(POSTGRES_ADDRESS, f"127.0.0.1:{proxy.port}")
        settings = hub_settings(tmp_path, database_url=proxied, access_token_ttl_s=2.0)
        with running_hub(settings) as base:
            token = access_token(base, "admin", ADMIN_PASSWORD)
            expires = time.time() + 2.0
            with api_client(base, token) as admin:
                assert admin.get("/api/v1/vehicles").status_code == 200
                proxy.cut()
                assert admin.get("/api/v1/vehicles").status_code == 200  # from the cache
                poll_until(lambda: time.time() > expires + 0.2, 10, "the token to expire")
                expired = admin.get("/api/v1/vehicles")
                proxy.start()
        assert expired.status_code == 503  # forgotten, and the database cannot answer
