"""Two hub processes on one PostgreSQL database and one NATS bus, a vehicle on hub A
(docs/deployer.md, "Several hubs")."""

from __future__ import annotations

import uuid
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path

import httpx

from gcs.launcher import FleetPlan, LocalFleet, free_port
from tests.conftest import scratch_postgres
from tests.support.api import access_token
from tests.support.hubs import TEST_HUB_ENV
from tests.support.waiting import poll_until

VEHICLE = "sim_1"


class FailoverFleet(LocalFleet):
    """A local fleet whose agents know a second hub."""

    def __init__(self, plan: FleetPlan, fallback_ws: str) -> None:
        super().__init__(plan)
        self.fallback_ws = fallback_ws

    def start_agent(self, index: int, sim_port: int) -> None:
        onboard = self.plan.data_dir / "onboard" / self.vehicle_id(index)
        self.spawn(
            f"agent_{index + 1}",
            [
                "agent",
                "--fcu",
                f"tcp:127.0.0.1:{sim_port}",
                "--hub",
                self.plan.hub_ws,
                "--hub-fallback",
                self.fallback_ws,
                "--vehicle-id",
                self.vehicle_id(index),
                "--telemetry-rate-hz",
                str(self.plan.telemetry_rate_hz),
                # Kept on disk while no hub has stored it: the failover loses nothing.
                "--outbox-dir",
                str(onboard),
            ],
            {"GCS_AGENT_TOKEN": self.plan.agent_token(index)},
        )


@dataclass
class TwoHubs:
    fleet: FailoverFleet
    a: str  # hub A's base URL
    b: str
    database_url: str
    start_b: Callable[[], None]  # hub B again, as the fixture started it
    bus_prefix: str

    def admin_token(self, base: str) -> str:
        return access_token(base, "admin", self.fleet.plan.admin_password)


def _wait_ready(fleet: LocalFleet, base: str, timeout_s: float = 60.0) -> None:
    def healthy() -> bool:
        fleet.check_alive()
        try:
            with httpx.Client(base_url=base, timeout=2) as client:
                return client.get("/api/v1/health").status_code == 200
        except httpx.TransportError:
            return False

    poll_until(healthy, timeout_s, f"the hub at {base}")


@contextmanager
def two_hubs(tmp_path: Path, bus_a: dict[str, str], bus_b: dict[str, str]) -> Iterator[TwoHubs]:
    """Hubs A and B on a fresh database, each joining the bus with its settings."""
    with scratch_postgres() as database_url:
        plan = FleetPlan(vehicles=1, port=free_port(), data_dir=tmp_path / "a", speedup=5.0)
        port_b = free_port()
        fleet = FailoverFleet(plan, f"ws://127.0.0.1:{port_b}")
        shared = {
            "DATABASE_URL": database_url,
            # One prefix per test: other tests and other helpers share the server.
            "GCS_BUS_PREFIX": f"t{uuid.uuid4().hex[:12]}",
            "GCS_VIZ_ENABLED": "false",
        }
        with fleet:
            plan.data_dir.mkdir(mode=0o700, parents=True)
            fleet.log_dir.mkdir(mode=0o700)
            # One after the other: the first creates the schema, the second finds it.
            fleet.start_hub({**TEST_HUB_ENV, **shared, **bus_a})
            _wait_ready(fleet, plan.hub_http)
            tokens = f"{VEHICLE}={plan.agent_token(0)}"
            hub_b = f"http://127.0.0.1:{port_b}"

            def start_b() -> None:
                fleet.spawn(
                    "hub_b",
                    ["hub", "--port", str(port_b), "--data-dir", str(tmp_path / "b")],
                    {
                        **shared,
                        **bus_b,
                        "GCS_ENVIRONMENT": "development",
                        "GCS_ADMIN_PASSWORD": plan.admin_password,
                        "GCS_AGENT_TOKENS": tokens,
                    },
                )
                _wait_ready(fleet, hub_b)

            start_b()
            fleet.start_vehicle(0)
            yield TwoHubs(
                fleet, plan.hub_http, hub_b, database_url, start_b, shared["GCS_BUS_PREFIX"]
            )
