"""ArduCopter 4.7 lists its own modes (AVAILABLE_MODES): the hub offers a standard
build's modes, not pymavlink's table of every mode ArduCopter ever had."""

from __future__ import annotations

import pytest

from gcs.launcher import LocalFleet
from tests.helpers import FleetWatcher, api_client, ready

pytestmark = pytest.mark.integration

# GCS_MAVLINK_Copter::send_available_mode for a build without FLOWHOLD, FOLLOW, ZIGZAG,
# SYSTEMID, AUTOROTATE and TURTLE, under the names the agent gives them (pymavlink's:
# ArduCopter's own "SMARTRTL" and "AUTO RTL" are SMART_RTL and AUTO_RTL).
ARDUCOPTER_STANDARD_BUILD = [
    "ACRO",
    "ALT_HOLD",
    "AUTO",
    "AUTOTUNE",
    "AUTO_RTL",
    "AVOID_ADSB",
    "BRAKE",
    "CIRCLE",
    "DRIFT",
    "FLIP",
    "GUIDED",
    "GUIDED_NOGPS",
    "LAND",
    "LOITER",
    "POSHOLD",
    "RTL",
    "SMART_RTL",
    "SPORT",
    "STABILIZE",
    "THROW",
]


def test_an_arducopter_lists_the_modes_its_build_has(
    fleet: LocalFleet, fleet_admin_token: str
) -> None:
    base = fleet.plan.hub_http
    vehicle = fleet.vehicle_id(0)
    with (
        FleetWatcher(base, fleet_admin_token) as watcher,
        api_client(base, fleet_admin_token) as api,
    ):
        watcher.wait_until(ready(vehicle), 60, f"{vehicle} ready")
        watcher.wait_until(
            lambda v: sorted(v[vehicle].get("modes", [])) == ARDUCOPTER_STANDARD_BUILD,
            20,
            "the autopilot's own list",
        )
        assert sorted(api.get(f"/api/v1/vehicles/{vehicle}").json()["modes"]) == (
            ARDUCOPTER_STANDARD_BUILD
        )
        for missing in ("ZIGZAG", "FOLLOW", "SYSTEMID", "TURTLE", "FLOWHOLD", "POSITION"):
            refused = api.post(
                f"/api/v1/vehicles/{vehicle}/commands", json={"name": "set_mode", "mode": missing}
            )
            assert refused.status_code == 422, refused.text
            assert f"unknown mode {missing!r}" in refused.text
