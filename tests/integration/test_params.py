"""Parameters through the hub, against the simulator's ArduCopter parameter table."""

from __future__ import annotations

import pytest

from gcs.launcher import LocalFleet
from tests.support.api import api_client
from tests.support.watcher import FleetWatcher

pytestmark = pytest.mark.integration

VEHICLE = "sim_2"


def test_read_all_read_one_and_set_with_echo(fleet: LocalFleet, fleet_admin_token: str) -> None:
    base = fleet.plan.hub_http
    with FleetWatcher(base, fleet_admin_token) as watcher:
        watcher.wait_until(lambda v: v.get(VEHICLE, {}).get("connected"), 30, f"{VEHICLE} online")
    with api_client(base, fleet_admin_token) as api:
        listing = api.get(f"/api/v1/vehicles/{VEHICLE}/params")
        assert listing.status_code == 200, listing.text
        values = listing.json()["values"]
        assert len(values) > 20
        assert {"WPNAV_SPEED", "RTL_ALT", "BATT_FS_LOW_ACT"} <= set(values)

        one = api.get(f"/api/v1/vehicles/{VEHICLE}/params/RTL_ALT").json()
        assert one["values"] == {"RTL_ALT": values["RTL_ALT"]}

        original = values["RTL_ALT"]
        changed = api.put(f"/api/v1/vehicles/{VEHICLE}/params/RTL_ALT", json={"value": 2500})
        assert changed.status_code == 200, changed.text
        assert changed.json()["values"]["RTL_ALT"] == 2500
        reread = api.get(f"/api/v1/vehicles/{VEHICLE}/params/RTL_ALT").json()["values"]
        assert reread["RTL_ALT"] == 2500
        api.put(f"/api/v1/vehicles/{VEHICLE}/params/RTL_ALT", json={"value": original})

        unknown = api.put(f"/api/v1/vehicles/{VEHICLE}/params/NO_SUCH_PARAM", json={"value": 1})
        assert unknown.status_code == 409
        assert "no parameter 'NO_SUCH_PARAM'" in unknown.json()["detail"]

        bad_name = api.get(f"/api/v1/vehicles/{VEHICLE}/params/lower_case")
        assert bad_name.status_code == 422
