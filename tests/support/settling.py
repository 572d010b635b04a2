"""A shared fleet brought to the state each test may assume, and a vehicle taken off."""

from __future__ import annotations

from collections.abc import Sequence

import httpx

from tests.support.api import api_client, send_command
from tests.support.watcher import FleetWatcher, on_the_ground, ready


def take_off(
    api: httpx.Client, watcher: FleetWatcher, vehicle: str, altitude: float, *, above: float
) -> None:
    """GUIDED, armed and climbing to ``altitude``; back once it is higher than ``above``."""
    for command in ({"name": "set_mode", "mode": "GUIDED"}, {"name": "arm"}):
        assert send_command(api, vehicle, **command)["status"] == "accepted"
    assert send_command(api, vehicle, name="takeoff", altitude=altitude)["status"] == "accepted"
    watcher.wait_until(
        lambda v: (v[vehicle]["state"]["alt_rel"] or 0) > above, 60, f"{vehicle} climbing"
    )


# -- a shared fleet as a test may assume it -------------------------------------------

# Surveys that hold their drones: planned (checked, nothing uploaded) or flying.
ACTIVE_SURVEY_STATES = ("planned", "flying", "handover_offered")
# A pack below this cannot fly a survey's mission past the rails: say so, not a 422 later.
SETTLED_BATTERY_PCT = 40.0


def settle_fleet(
    base_url: str, token: str, vehicles: Sequence[str], timeout_s: float = 120
) -> None:
    """Bring a fleet that tests share to the state each may assume: no survey holding a
    drone, every vehicle connected, landed and disarmed (on the ground as its autopilot
    says), nobody flying one by hand, and a pack to fly on. A vehicle still armed or in
    the air is landed where it is; one already settled costs a look, nothing more."""
    with api_client(base_url, token) as api, FleetWatcher(base_url, token) as watcher:
        for survey in api.get("/api/v1/surveys").json()["surveys"]:
            if survey["state"] in ACTIVE_SURVEY_STATES:
                aborted = api.post(f"/api/v1/surveys/{survey['survey_id']}/abort")
                assert aborted.status_code == 200, aborted.text
        watcher.wait_until(
            lambda v: all(ready(vehicle)(v) for vehicle in vehicles),
            timeout_s,
            "the fleet connected and reporting",
        )
        up = [vehicle for vehicle in vehicles if not on_the_ground(vehicle)(watcher.vehicles)]
        if up:
            # Each vehicle's own answer is not checked: one may be landing already, and
            # the wait below is what counts.
            landing = {"vehicle_ids": up, "command": {"name": "land"}}
            answer = api.post("/api/v1/fleet/commands", json=landing)
            assert answer.status_code == 200, answer.text
        watcher.wait_until(
            lambda v: (
                all(on_the_ground(vehicle)(v) for vehicle in vehicles)
                and not any(watcher.lease_holders.get(vehicle) for vehicle in vehicles)
            ),
            timeout_s,
            f"{', '.join(vehicles)} landed and disarmed, with no lease held",
        )
        low = {
            vehicle: battery
            for vehicle in vehicles
            if (battery := watcher.state(vehicle)["battery_remaining"]) < SETTLED_BATTERY_PCT
        }
        assert not low, f"packs below {SETTLED_BATTERY_PCT:g} %, too low to fly on: {low}"


# -- processes -------------------------------------------------------------------------
