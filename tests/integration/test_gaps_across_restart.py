"""A gap still waited for when the hub dies is still waited for after it restarts, so
the loss the agent then reports is recorded (12.13). A real hub process, killed -9."""

from __future__ import annotations

from pathlib import Path

import pytest

from gcs.launcher import FleetPlan, LocalFleet, free_port
from protocol.messages import Unavailable, encode
from tests.support.agents import scripted_agent, telemetry_frame
from tests.support.api import access_token, api_client
from tests.support.delivery import _acked, _next
from tests.support.hubs import TEST_HUB_ENV

pytestmark = pytest.mark.integration


def test_an_open_gap_survives_a_hub_killed_and_restarted(tmp_path: Path) -> None:
    plan = FleetPlan(vehicles=0, port=free_port(), data_dir=tmp_path)
    with LocalFleet(plan) as fleet:
        fleet.start(TEST_HUB_ENV)
        fleet.wait_until_ready()
        admin = access_token(plan.hub_http, "admin", plan.admin_password)
        with api_client(plan.hub_http, admin) as api:
            token = api.post("/api/v1/vehicles/gappy/agent-tokens").json()["token"]

        with scripted_agent(plan.hub_http, "gappy", token, delivery=True) as agent:
            for seq in (0, 1, 2, 7, 8, 9):
                agent.send(telemetry_frame(seq))
            resend = _next(agent, lambda frame: frame["type"] == "resend")
            assert (resend["first_seq"], resend["last_seq"]) == (3, 6)
            # The hub dies before the agent answers: no flush, no goodbye.
            fleet.kill("hub")

        fleet.start_hub(TEST_HUB_ENV)
        fleet.wait_until_ready()
        with scripted_agent(plan.hub_http, "gappy", token, delivery=True) as agent:
            # As the agent does on reconnecting: what was never acknowledged, again.
            for seq in (7, 8, 9, 10):
                agent.send(telemetry_frame(seq))
            resend = _next(agent, lambda frame: frame["type"] == "resend")
            assert (resend["stream_id"], resend["first_seq"], resend["last_seq"]) == ("s1", 3, 6)
            lost = Unavailable(
                stream_id="s1", kind="telemetry", first_seq=3, last_seq=6, reason="outbox full"
            )
            agent.send(encode(lost))
            _next(agent, _acked("telemetry", 10))

        admin = access_token(plan.hub_http, "admin", plan.admin_password)
        with api_client(plan.hub_http, admin) as api:
            events = api.get("/api/v1/events", params={"vehicle_id": "gappy", "kind": "data_lost"})
            samples = api.get("/api/v1/vehicles/gappy/telemetry").json()["samples"]
    texts = [event["text"] for event in events.json()["events"]]
    assert texts == ["telemetry samples 3-6 of stream s1 never arrived: outbox full"]
    assert sorted(sample["seq"] for sample in samples) == [0, 1, 2, 7, 8, 9, 10]


def test_a_reconnecting_agent_is_asked_for_open_gaps_before_it_sends_anything(
    tmp_path: Path,
) -> None:
    """An agent restarted without its outbox never sends on the old stream again; the
    hub must still ask it, or that loss would never be recorded."""
    plan = FleetPlan(vehicles=0, port=free_port(), data_dir=tmp_path)
    with LocalFleet(plan) as fleet:
        fleet.start(TEST_HUB_ENV)
        fleet.wait_until_ready()
        admin = access_token(plan.hub_http, "admin", plan.admin_password)
        with api_client(plan.hub_http, admin) as api:
            token = api.post("/api/v1/vehicles/quiet/agent-tokens").json()["token"]
        with scripted_agent(plan.hub_http, "quiet", token, delivery=True) as agent:
            for seq in (0, 5):
                agent.send(telemetry_frame(seq))
            _next(agent, lambda frame: frame["type"] == "resend")
            fleet.kill("hub")

        fleet.start_hub(TEST_HUB_ENV)
        fleet.wait_until_ready()
        with scripted_agent(plan.hub_http, "quiet", token, delivery=True) as agent:
            resend = _next(agent, lambda frame: frame["type"] == "resend")
            assert (resend["first_seq"], resend["last_seq"]) == (1, 4)
            agent.send(
                encode(
                    Unavailable(
                        stream_id="s1", kind="telemetry", first_seq=1, last_seq=4, reason="gone"
                    )
                )
            )
            _next(agent, _acked("telemetry", 5))
