"""ArduCopter 4.7 lists its own modes (AVAILABLE_MODES): the hub offers a standard
build's modes, not pymavlink's table of every mode ArduCopter ever had."""

from __future__ import annotations

import asyncio
import contextlib

import pytest

from gcs.launcher import LocalFleet
from simulator import ListenAddress, SimulatorConfig
from tests.support.api import api_client
from tests.support.simulators import serving
from tests.support.watcher import FleetWatcher, ready
from vehicle_agents.fcu.available_modes import AvailableModes
from vehicle_agents.fcu.link import FcuLink

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


def test_arducopters_modes_are_read_one_by_one_when_asking_for_all_brings_one() -> None:
    """ArduCopter 4.7 answers a request for every mode (param2 0) with its first mode
    alone (the simulator's ArduPilot personality does as SITL did): the agent asks for the
    rest by index, and the autopilot's own list replaces the fixed table."""

    async def run() -> None:
        with serving(SimulatorConfig(listen=ListenAddress("tcp", "127.0.0.1", 0))) as (
            _server,
            address,
        ):
            link = FcuLink(f"tcp:127.0.0.1:{address.port}")
            running = asyncio.create_task(link.run())
            try:
                await asyncio.wait_for(link.wait_identified(), 10)
                reported: asyncio.Queue[list[str]] = asyncio.Queue()
                lister = AvailableModes(link, lambda table: reported.put_nowait(table.names))
                listing = asyncio.create_task(lister.run())
                try:
                    assert await asyncio.wait_for(reported.get(), 20) == (ARDUCOPTER_STANDARD_BUILD)
                    assert lister.answered is True
                    assert link.modes is not None
                    assert link.modes.reported
                finally:
                    listing.cancel()
            finally:
                running.cancel()
                with contextlib.suppress(asyncio.CancelledError):
                    await running

    asyncio.run(run())
