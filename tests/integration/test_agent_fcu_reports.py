"""What the agent reports from what the flight controller says, over real MAVLink bytes:
PX4's repeated MISSION_ITEM_REACHED and chunked STATUSTEXTs as single events, no mission
progress without a mission, no position before the autopilot has one, and the
autopilot's own mode list read again when it changes. Its photos' events are
test_agent_camera_events.py's.

`ScriptedFlightController` (tests/support/mavlink_peer.py) sends what each case pushes; the
agent's `FcuLink` and `EventSource` run in-process (tests/support/fcu_reports.py) and
their events are read back from a real `Outbox`.
"""

from __future__ import annotations

import asyncio
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest
from pymavlink.dialects.v20 import ardupilotmega as mavlink2
from pymavlink.dialects.v20 import development

from tests.support.api import api_client
from tests.support.fcu_reports import (
    ARDUPILOT,
    LAT,
    LON,
    NO_MISSION,
    PX4,
    agent_on,
    current,
    reached,
    text,
)
from tests.support.mavlink_peer import ScriptedFlightController, _is_command
from tests.support.processes import agent_process
from tests.support.waiting import poll_until
from tests.support.watcher import FleetWatcher, state_of
from vehicle_agents.fcu.available_modes import AvailableModes
from vehicle_agents.fcu.messages import MavMessage
from vehicle_agents.telemetry.snapshot import link_snapshot

pytestmark = pytest.mark.integration


# -- 12.21: a reached item is one event per pass -----------------------------------------


def test_px4s_repeated_reached_item_is_one_event_per_pass() -> None:
    async def run() -> None:
        with ScriptedFlightController(autopilot=PX4) as fcu:
            async with agent_on(fcu) as agent:
                # As PX4 does: MISSION_CURRENT moves on, the reached item is sent, and then
                # ten more times at 1 Hz along with MISSION_CURRENT.
                fcu.push(current(2, 4), reached(1))
                for _ in range(10):
                    fcu.push(current(2, 4), reached(1))
                fcu.push(current(3, 4), reached(2), reached(2), current(3, 4), reached(2))
                # a DO_JUMP back to item seq 1: reaching it again is a new pass
                fcu.push(current(1, 4), current(2, 4), reached(1), current(2, 4), reached(1))
                events = await agent.events(3)
                await agent.no_more_events()
        assert [(e["kind"], e["mission_item"], e["text"]) for e in events] == [
            ("mission", 2, "reached mission item 2"),  # PX4 numbers from 0, the hub from 1
            ("mission", 3, "reached mission item 3"),
            ("mission", 2, "reached mission item 2"),
        ]

    asyncio.run(run())


# -- 12.22: chunked STATUSTEXTs are joined -----------------------------------------------


def test_chunked_statustexts_become_one_event_each() -> None:
    first = "RTL: start return at 520 m (30 m above destination"
    exact = "x" * 50 + "y" * 50  # two full chunks: no chunk says it is the last

    async def run() -> None:
        with ScriptedFlightController(autopilot=PX4) as fcu:
            async with agent_on(fcu) as agent:
                fcu.push(text(first, 7, 0), text(")", 7, 1))
                fcu.push(text("Takeoff detected"))  # id 0: complete in itself
                # chunks out of order, another text's chunks in between
                # One push: the sets are complete within the agent's 1 s wait, however
                # busy the machine.
                fcu.push(
                    text("b" * 50, 9, 1),
                    text("tail", 8, 1),
                    text("a" * 50, 9, 0),
                    text("head of 8 " + "h" * 40, 8, 0),
                    text("end", 9, 2),
                )
                fcu.push(text(exact[:50], 10, 0), text(exact[50:], 10, 1))
                events = await agent.events(5)
                await agent.no_more_events()
        assert [(e["kind"], e["text"]) for e in events] == [
            ("statustext", first + ")"),
            ("statustext", "Takeoff detected"),
            ("statustext", "head of 8 " + "h" * 40 + "tail"),
            ("statustext", "a" * 50 + "b" * 50 + "end"),
            ("statustext", exact),  # let out after the wait, on a later heartbeat
        ]
        assert all(e["severity"] == mavlink2.MAV_SEVERITY_INFO for e in events)

    asyncio.run(run())


# -- 12.23: no mission progress without a mission ----------------------------------------


@pytest.mark.parametrize(
    ("autopilot", "empty"),
    [
        (PX4, current(0, 65535, 0)),  # PX4: total UINT16_MAX without a mission
        (ARDUPILOT, current(0, 0, NO_MISSION)),  # ArduPilot: 0 items after home
    ],
    ids=["px4", "ardupilot"],
)
def test_no_mission_progress_without_a_mission(autopilot: int, empty: MavMessage) -> None:
    async def run() -> None:
        with ScriptedFlightController(autopilot=autopilot) as fcu:
            async with agent_on(fcu) as agent:
                fcu.push(empty)
                await agent.received("MISSION_CURRENT")
                state = link_snapshot(agent.link)
                assert (state.mission_current, state.mission_total) == (None, None)
                fcu.push(current(2, 4))  # a mission of 4 items is uploaded and flown
                state = await agent.state_until(lambda s: s.mission_total == 4)
                assert state.mission_current == (3 if autopilot == PX4 else 2)
                fcu.push(empty)  # and cleared
                state = await agent.state_until(lambda s: s.mission_total is None)
                assert state.mission_current is None

    asyncio.run(run())


# -- 12.24: no position before the autopilot has one -------------------------------------


class PositionedFlightController(ScriptedFlightController):
    """Streams GLOBAL_POSITION_INT as the test sets it: None sends none (PX4 without a
    global position), (0, 0) is ArduPilot's before its EKF has an origin."""

    position: tuple[int, int] | None = (0, 0)

    def telemetry(self) -> list[MavMessage]:
        messages = super().telemetry()
        if self.position is not None:
            lat, lon = self.position
            relative_alt = 0 if (lat, lon) == (0, 0) else 120
            messages.append(
                mavlink2.MAVLink_global_position_int_message(
                    1000, lat, lon, 0, relative_alt, 0, 0, 0, 9000
                )
            )
        return messages


def test_no_position_is_reported_until_the_autopilot_has_one() -> None:
    async def run() -> None:
        fcu = PositionedFlightController()
        with fcu:
            async with agent_on(fcu) as agent:
                await agent.received("GLOBAL_POSITION_INT")
                state = link_snapshot(agent.link)
                assert (state.lat, state.lon, state.alt_msl, state.alt_rel) == (None,) * 4
                fcu.position = (LAT, LON)  # the EKF has its origin
                state = await agent.state_until(lambda s: s.lat is not None)
                assert (state.lat, state.lon) == (LAT / 1e7, LON / 1e7)
                assert state.alt_rel == 0.12
                fcu.position = None  # PX4 loses its global position: the message stops
                state = await agent.state_until(lambda s: s.lat is None)
                assert state.fcu_connected
                assert state.alt_rel is None

    asyncio.run(run())


# -- the whole way: agent process, hub, storage ------------------------------------------


def test_the_hub_stores_no_position_and_one_reached_event_with_its_item(
    hub: str, admin_token: str, enrol: Callable[[str], str], tmp_path: Path
) -> None:
    vehicle = "no-origin"
    fcu = PositionedFlightController()  # ArduPilot, its EKF without an origin: zeros
    with (
        fcu,
        agent_process(hub, enrol(vehicle), vehicle, fcu.port, log_dir=tmp_path),
        FleetWatcher(hub, admin_token) as watcher,
        api_client(hub, admin_token) as api,
    ):
        watcher.wait_until(
            lambda v: state_of(v, vehicle).get("fcu_connected") is True, 30, "the vehicle"
        )
        fcu.push(current(3, 4), *[reached(2), current(3, 4)] * 5)  # sent again and again

        def stored() -> tuple[list[dict[str, Any]], list[dict[str, Any]]]:
            events = api.get("/api/v1/events", params={"vehicle_id": vehicle, "kind": "mission"})
            series = api.get(
                "/api/v1/telemetry/series", params={"vehicle_id": vehicle, "metric": "alt_rel"}
            )
            return events.json()["events"], series.json()["series"].get(vehicle, [])

        poll_until(lambda: stored()[0], 30, "the reached item stored")
        # two more seconds of samples stored: every repeat has long arrived
        before = len(stored()[1])
        poll_until(lambda: len(stored()[1]) >= before + 20, 30, "more telemetry stored")
        events, samples = stored()
        assert [(e["mission_item"], e["text"]) for e in events] == [(2, "reached mission item 2")]
        assert {(s["lat"], s["lon"], s["alt_msl"]) for s in samples} == {(None, None, None)}
        summary = api.get(f"/api/v1/vehicles/{vehicle}").json()
        assert (summary["state"]["lat"], summary["state"]["lon"]) == (None, None)


# -- the autopilot's own mode list (AVAILABLE_MODES) -------------------------------------


class ListingFlightController(ScriptedFlightController):
    """Answers MAV_CMD_REQUEST_MESSAGE for AVAILABLE_MODES (param2 0) as PX4 does: every
    mode of ``modes`` (main, sub, name, properties), numbered 1..N."""

    modes: tuple[tuple[int, int, str, int], ...] = ()

    def _answer(self, message: MavMessage, now: float) -> list[tuple[float, MavMessage]]:
        answers = super()._answer(message, now)
        if _is_command(message, mavlink2.MAV_CMD_REQUEST_MESSAGE) and message.param1 == 435:
            total = len(self.modes)
            answers += [
                (
                    now,
                    development.MAVLink_available_modes_message(
                        total, index, 0, (main << 16) | (sub << 24), properties, name.encode()
                    ),
                )
                for index, (main, sub, name, properties) in enumerate(self.modes, start=1)
            ]
        return answers


def test_the_mode_list_is_read_again_when_the_autopilots_monitor_says_it_changed() -> None:
    """After the link comes up the agent asks for every mode (REQUEST_MESSAGE 435, param2
    0); when AVAILABLE_MODES_MONITOR's seq moves (a PX4 external mode registered) it asks
    again, and the new list replaces the table and is reported. Modes the autopilot marks
    NOT_USER_SELECTABLE are left out."""

    async def run() -> None:
        with ListingFlightController(autopilot=PX4) as fcu:
            fcu.modes = ((3, 0, "", 0), (4, 3, "Hold", 1), (1, 0, "Termination", 2))
            async with agent_on(fcu) as agent:
                reported: asyncio.Queue[list[str]] = asyncio.Queue()
                lister = AvailableModes(agent.link, lambda table: reported.put_nowait(table.names))
                task = asyncio.create_task(lister.run())
                try:
                    assert await asyncio.wait_for(reported.get(), 5) == ["LOITER", "POSCTL"]
                    [asked] = fcu.commands(mavlink2.MAV_CMD_REQUEST_MESSAGE)
                    assert (asked.param1, asked.param2) == (435, 0)
                    fcu.modes += ((4, 11, "My Survey", 0),)  # a ROS 2 mode registers
                    fcu.push(development.MAVLink_available_modes_monitor_message(1))  # as it was
                    fcu.push(development.MAVLink_available_modes_monitor_message(2))  # changed
                    changed = await asyncio.wait_for(reported.get(), 5)
                    assert changed == ["LOITER", "MY_SURVEY", "POSCTL"]
                    assert agent.link.modes is not None
                    assert agent.link.modes.settings["MY_SURVEY"].custom_sub_mode == 11
                finally:
                    task.cancel()

    asyncio.run(run())
