"""The agent's mission exchange against the simulator over real TCP, as ArduPilot and as
PX4 store and give back missions: a round trip returns what was sent (frames included),
and a vehicle that holds no mission downloads as home alone."""

from __future__ import annotations

import asyncio
import contextlib
from collections.abc import Awaitable, Callable
from typing import TypeVar

import pytest
from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from protocol.messages import MissionItem
from simulator import ListenAddress, SimulatorConfig
from simulator.config import Autopilot
from tests.support.simulators import SYSID, serving
from vehicle_agents.fcu.link import FcuLink
from vehicle_agents.fcu.missions import MissionClient

pytestmark = pytest.mark.integration

TAKEOFF = mavlink2.MAV_CMD_NAV_TAKEOFF
WAYPOINT = mavlink2.MAV_CMD_NAV_WAYPOINT
RTL = mavlink2.MAV_CMD_NAV_RETURN_TO_LAUNCH
CHANGE_SPEED = mavlink2.MAV_CMD_DO_CHANGE_SPEED
GLOBAL = mavlink2.MAV_FRAME_GLOBAL
RELATIVE = mavlink2.MAV_FRAME_GLOBAL_RELATIVE_ALT
RELATIVE_INT = mavlink2.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT
HOME_LAT, HOME_LON = -35.363262, 149.165237
T = TypeVar("T")


def with_missions(autopilot: Autopilot, body: Callable[[MissionClient], Awaitable[T]]) -> T:
    config = SimulatorConfig(
        listen=ListenAddress("tcp", "127.0.0.1", 0), system_id=SYSID, autopilot=autopilot
    )

    async def run(port: int) -> T:
        link = FcuLink(f"tcp:127.0.0.1:{port}")
        running = asyncio.create_task(link.run())
        try:
            await asyncio.wait_for(link.wait_identified(), 10)
            while link.latest.get("HOME_POSITION") is None:
                await link.wait_for(lambda m: m.get_type() == "HOME_POSITION", 5)
            return await body(MissionClient(link))
        finally:
            running.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await running

    with serving(config) as (_server, address):
        return asyncio.run(run(address.port))


@pytest.mark.parametrize("autopilot", ["ardupilot", "px4"])
def test_a_round_trip_gives_back_the_frames_that_were_sent(autopilot: Autopilot) -> None:
    """Frame 6 comes back from ArduPilot as 3 (AP_Mission keeps "relative", not the message
    form) and 3 from PX4 as 6: the hub's one form is the plain frame, both ways."""
    sent = [
        # where it stands: PX4 flies to a take-off's position (0, 0 is refused)
        MissionItem(command=TAKEOFF, frame=RELATIVE_INT, lat=HOME_LAT, lon=HOME_LON, alt=10),
        MissionItem(
            command=WAYPOINT, frame=RELATIVE_INT, lat=HOME_LAT + 3e-4, lon=HOME_LON, alt=12
        ),
        MissionItem(command=WAYPOINT, frame=GLOBAL, lat=HOME_LAT, lon=HOME_LON + 3e-4, alt=600),
        MissionItem(command=WAYPOINT, frame=RELATIVE, lat=HOME_LAT, lon=HOME_LON, alt=15),
        MissionItem(command=RTL, frame=RELATIVE),
    ]

    async def body(client: MissionClient) -> list[MissionItem]:
        uploaded = await client.upload(sent)
        assert uploaded.status == "accepted", uploaded
        downloaded = await client.download()
        assert downloaded.status == "accepted", downloaded
        assert downloaded.items is not None
        return downloaded.items[1:]

    back = with_missions(autopilot, body)
    assert [item.model_copy(update={"lat": round(item.lat, 7)}) for item in back] == [
        item.model_copy(update={"lat": round(item.lat, 7)}) for item in sent
    ]
    assert [item.frame for item in sent] == [RELATIVE, RELATIVE, GLOBAL, RELATIVE, RELATIVE]


@pytest.mark.parametrize("autopilot", ["ardupilot", "px4"])
def test_an_unset_yaw_goes_as_nan_and_comes_back_unset(autopilot: Autopilot) -> None:
    """null is MAVLink's NaN ("keep the heading" for a yaw): sent as NaN, read back as
    null, never 0 (on PX4 a yaw of 0 turns the vehicle north at every waypoint)."""
    sent = [
        MissionItem(command=TAKEOFF, lat=HOME_LAT, lon=HOME_LON, alt=10, param4=None),
        MissionItem(command=WAYPOINT, lat=HOME_LAT + 3e-4, lon=HOME_LON, alt=12, param4=None),
        MissionItem(command=WAYPOINT, lat=HOME_LAT, lon=HOME_LON + 3e-4, alt=12, param4=90),
    ]

    async def body(client: MissionClient) -> list[MissionItem]:
        uploaded = await client.upload(sent)
        assert uploaded.status == "accepted", uploaded
        downloaded = await client.download()
        assert downloaded.status == "accepted", downloaded
        assert downloaded.items is not None
        return downloaded.items[1:]

    back = with_missions(autopilot, body)
    assert [item.param4 for item in back] == [None, None, 90]


@pytest.mark.parametrize("autopilot", ["ardupilot", "px4"])
def test_a_vehicle_without_a_mission_downloads_as_home_alone(autopilot: Autopilot) -> None:
    async def body(client: MissionClient) -> tuple[str, list[MissionItem]]:
        cleared = await client.clear()
        assert cleared.status == "accepted", cleared
        downloaded = await client.download()
        assert downloaded.status == "accepted", downloaded
        assert downloaded.items is not None
        return downloaded.message, downloaded.items

    message, items = with_missions(autopilot, body)
    assert message == "0 items (plus home)"
    [home] = items
    assert (home.lat, home.lon) == pytest.approx((HOME_LAT, HOME_LON), abs=1e-6)


@pytest.mark.parametrize("autopilot", ["ardupilot", "px4"])
def test_a_new_mission_starts_from_its_first_item(autopilot: Autopilot) -> None:
    """PX4 keeps the index it had when a changed mission arrives with no item flagged
    current (real PX4 SITL flew a new survey's upload from the old one's last item:
    "Mission finished" at once, then RTL): the agent flags the first item."""
    first = [
        MissionItem(command=TAKEOFF, lat=HOME_LAT, lon=HOME_LON, alt=10),
        *(
            MissionItem(command=WAYPOINT, lat=HOME_LAT + k * 1e-4, lon=HOME_LON, alt=12)
            for k in range(1, 6)
        ),
    ]
    second = [item.model_copy(update={"alt": item.alt + 5}) for item in first]

    async def body(client: MissionClient) -> int:
        assert (await client.upload(first)).status == "accepted"
        moved = await client.set_current(5)
        assert moved.status == "accepted", moved
        assert (await client.upload(second)).status == "accepted"
        link = client.link
        await link.wait_for(lambda m: m.get_type() == "MISSION_CURRENT", 5)
        current = await link.wait_for(lambda m: m.get_type() == "MISSION_CURRENT", 5)
        assert current is not None
        return int(current.seq)

    assert with_missions(autopilot, body) == 0
