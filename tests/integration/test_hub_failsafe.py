"""The hub-link failsafe: the hub dies while a copter hovers; after the configured time
the agent commands RTL, and tells the hub what it did once the hub is back."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import pytest

from gcs.launcher import LocalFleet
from tests.support.api import access_token, api_client
from tests.support.hubs import TEST_HUB_ENV
from tests.support.processes import running_fleet, spilled_frames
from tests.support.waiting import poll_until
from tests.support.watcher import FleetWatcher, ready

pytestmark = [pytest.mark.integration, pytest.mark.slow]

VEHICLE = "sim_1"


@pytest.fixture
def rtl_on_hub_loss(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Iterator[LocalFleet]:
    # The agents read these from the environment, as they would from a systemd unit.
    monkeypatch.setenv("GCS_AGENT_HUB_FAILSAFE_ACTION", "rtl")
    monkeypatch.setenv("GCS_AGENT_HUB_FAILSAFE_TIMEOUT_S", "2")
    with running_fleet(tmp_path, vehicles=1, speedup=4.0) as fleet:
        yield fleet


def test_lost_hub_link_triggers_rtl_and_is_reported_on_reconnect(
    rtl_on_hub_loss: LocalFleet,
) -> None:
    fleet = rtl_on_hub_loss
    base = fleet.plan.hub_http
    token = access_token(base, "admin", fleet.plan.admin_password)
    with FleetWatcher(base, token) as watcher, api_client(base, token) as api:
        watcher.wait_until(ready(VEHICLE), 60, f"{VEHICLE} ready")
        takeoff = api.post(
            f"/api/v1/vehicles/{VEHICLE}/commands", json={"name": "takeoff", "altitude": 15}
        )
        assert takeoff.json()["outcome"]["status"] == "accepted", takeoff.text
        watcher.wait_until(lambda v: (v[VEHICLE]["state"]["alt_rel"] or 0) > 12, 60, "climb")

    fleet.kill("hub")
    poll_until(
        lambda: any(
            frame.kind == "event" and "commanded RTL" in frame.body
            for frame in spilled_frames(fleet, VEHICLE)
        ),
        30,
        "the agent to act on the lost hub link",
    )

    fleet.start_hub(TEST_HUB_ENV)
    fleet.wait_until_ready()
    token = access_token(base, "admin", fleet.plan.admin_password)
    with FleetWatcher(base, token) as watcher, api_client(base, token) as api:
        watcher.wait_until(
            lambda v: (v.get(VEHICLE, {}).get("state") or {}).get("mode") == "RTL",
            30,
            "the vehicle to be seen returning",
        )

        def failsafe_texts() -> list[str]:
            events = api.get("/api/v1/events", params={"vehicle_id": VEHICLE, "kind": "failsafe"})
            return [event["text"] for event in events.json()["events"]]

        poll_until(
            # this outage's report: a slow hub start can have made one of its own before
            lambda: any(
                "on losing it the agent commanded RTL" in text for text in failsafe_texts()
            ),
            30,
            "the failsafe's report to be stored",
        )
        texts = failsafe_texts()
    assert any("hub link lost for 2 s: commanded RTL" in text for text in texts)
    assert any("on losing it the agent commanded RTL" in text for text in texts)
