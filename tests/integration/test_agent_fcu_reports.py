"""What the agent reports from what the flight controller says, over real MAVLink bytes:
PX4's repeated MISSION_ITEM_REACHED and chunked STATUSTEXTs as single events, no mission
progress without a mission, and no position before the autopilot has one.

`ScriptedFlightController` (tests/mavlink_peer.py) sends what each case pushes; the
agent's `FcuLink` and `EventSource` run in-process and their events are read back from a
real `Outbox`.
"""

from __future__ import annotations

import asyncio
import contextlib
import json
import time
from collections.abc import AsyncIterator, Callable
from pathlib import Path
from typing import Any

import pytest
from pymavlink.dialects.v20 import ardupilotmega as mavlink2
from pymavlink.dialects.v20 import development

from protocol.messages import VehicleState
from tests.mavlink_peer import ScriptedFlightController, _is_command
from tests.support.api import api_client
from tests.support.processes import agent_process
from tests.support.waiting import poll_until
from tests.support.watcher import FleetWatcher, state_of
from vehicle_agents.agent import EventSource
from vehicle_agents.fcu.available_modes import AvailableModes
from vehicle_agents.fcu.link import FcuLink
from vehicle_agents.fcu.messages import MavMessage
from vehicle_agents.hub.outbox import Outbox
from vehicle_agents.telemetry.snapshot import link_snapshot

pytestmark = pytest.mark.integration

PX4 = mavlink2.MAV_AUTOPILOT_PX4
ARDUPILOT = mavlink2.MAV_AUTOPILOT_ARDUPILOTMEGA
NO_MISSION = mavlink2.MISSION_STATE_NO_MISSION
ACTIVE = mavlink2.MISSION_STATE_ACTIVE
LAT, LON = -353632620, 1491652370


class Agent:
    """The agent's FCU side, in-process: its link, its events, its snapshot."""

    def __init__(self, link: FcuLink, outbox: Outbox) -> None:
        self.link, self.outbox = link, outbox

    async def events(self, count: int, timeout_s: float = 5.0) -> list[dict[str, Any]]:
        got: list[dict[str, Any]] = []
        async with asyncio.timeout(timeout_s):
            while len(got) < count:
                got.append(json.loads(await self.outbox.next_frame()))
        return got

    async def no_more_events(self, quiet_s: float = 1.5) -> None:
        with contextlib.suppress(TimeoutError):
            async with asyncio.timeout(quiet_s):
                extra = json.loads(await self.outbox.next_frame())
                raise AssertionError(f"unexpected event {extra}")

    async def state_until(
        self, check: Callable[[VehicleState], bool], timeout_s: float = 8.0
    ) -> VehicleState:
        deadline = time.monotonic() + timeout_s
        while not check(state := link_snapshot(self.link)):
            assert time.monotonic() < deadline, f"state never matched: {state}"
            await self.link.wait_for(lambda m: True, 0.5)
        return state

    async def received(self, kind: str, timeout_s: float = 5.0) -> MavMessage:
        message = await self.link.wait_for(lambda m: m.get_type() == kind, timeout_s)
        assert message is not None, f"no {kind} arrived"
        return message


@contextlib.asynccontextmanager
async def agent_on(
    fcu: ScriptedFlightController, *, has_image_source: bool = True
) -> AsyncIterator[Agent]:
    link = FcuLink(f"tcp:127.0.0.1:{fcu.port}")
    running = asyncio.create_task(link.run())
    try:
        await asyncio.wait_for(link.wait_identified(), 10)
        assert link.modes is not None
        outbox = Outbox("test", 1000)
        events = EventSource(outbox, link.modes.autopilot, has_image_source=has_image_source)
        link.listeners.append(events.on_message)
        yield Agent(link, outbox)
    finally:
        running.cancel()
        with contextlib.suppress(asyncio.CancelledError):
            await running


def current(seq: int, total: int, state: int = ACTIVE) -> MavMessage:
    return mavlink2.MAVLink_mission_current_message(seq, total, state, 0)


def reached(seq: int) -> MavMessage:
    return mavlink2.MAVLink_mission_item_reached_message(seq)


def text(body: str, text_id: int = 0, chunk: int = 0) -> MavMessage:
    return mavlink2.MAVLink_statustext_message(
        mavlink2.MAV_SEVERITY_INFO, body.encode(), text_id, chunk
    )


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


# -- issue 17: each photo the camera takes is an event with its place --------------------


def feedback(index: int, target_system: int, flags: int) -> MavMessage:
    # As AP_Camera::send_feedback fills it: target_system is the vehicle's own id.
    return mavlink2.MAVLink_camera_feedback_message(
        0, target_system, 0, index, LAT, LON, 620.5, 30.25, 0, 0, 90, 0, flags, index
    )


def test_camera_feedback_becomes_a_camera_event_with_the_photo() -> None:
    async def run() -> None:
        with ScriptedFlightController(autopilot=ARDUPILOT) as fcu:
            async with agent_on(fcu) as agent:
                fcu.push(
                    feedback(1, fcu.system_id, mavlink2.CAMERA_FEEDBACK_PHOTO),
                    feedback(2, fcu.system_id, mavlink2.CAMERA_FEEDBACK_VIDEO),
                    feedback(3, fcu.system_id, mavlink2.CAMERA_FEEDBACK_PHOTO),
                )
                events = await agent.events(2)
                await agent.no_more_events()
        assert [e["kind"] for e in events] == ["camera", "camera"]
        assert events[0]["photo"] == {
            "index": 1,
            "lat": LAT / 1e7,
            "lon": LON / 1e7,
            "alt_rel": 30.25,
        }
        assert events[1]["photo"]["index"] == 3
        assert events[0]["text"].startswith("photo 1 at -35.3632620, 149.1652370")

    asyncio.run(run())


def test_camera_feedback_without_an_image_source_is_counted_and_said_once() -> None:
    """SITL's camera (ArduPilot's CAM1_TYPE 1, PX4's TRIG_INTERFACE 3) tells of each
    shutter with no image anywhere: the agent without --camera counts each, and says
    once that no image will follow."""

    async def run() -> None:
        with ScriptedFlightController(autopilot=ARDUPILOT) as fcu:
            async with agent_on(fcu, has_image_source=False) as agent:
                fcu.push(
                    feedback(1, fcu.system_id, mavlink2.CAMERA_FEEDBACK_PHOTO),
                    feedback(2, fcu.system_id, mavlink2.CAMERA_FEEDBACK_PHOTO),
                )
                events = await agent.events(3)
                await agent.no_more_events()
        assert [e["kind"] for e in events] == ["camera", "upload", "camera"]
        assert events[1]["text"] == (
            "photo 1: the autopilot's camera fired, but no image source is configured "
            "(--camera): shots are counted, no image is uploaded"
        )
        assert events[1]["severity"] == mavlink2.MAV_SEVERITY_NOTICE

    asyncio.run(run())


def test_px4s_camera_trigger_becomes_a_camera_event_where_the_drone_was() -> None:
    """PX4's CAMERA_TRIGGER carries no position: the photo is placed at the latest
    GLOBAL_POSITION_INT; none is reported before the autopilot has a position."""

    async def run() -> None:
        with ScriptedFlightController(autopilot=PX4) as fcu:
            async with agent_on(fcu) as agent:
                fcu.push(mavlink2.MAVLink_camera_trigger_message(0, 0))  # no position yet
                await agent.no_more_events()
                fcu.push(
                    mavlink2.MAVLink_global_position_int_message(
                        1000, LAT, LON, 614_500, 30_250, 0, 0, 0, 0
                    ),
                    mavlink2.MAVLink_camera_trigger_message(1_764_288_000_000_000, 1),
                )
                events = await agent.events(1)
        assert events[0]["kind"] == "camera"
        assert events[0]["photo"] == {
            "index": 1,
            "lat": LAT / 1e7,
            "lon": LON / 1e7,
            "alt_rel": 30.25,
        }

    asyncio.run(run())


def captured(index: int, lat: int = LAT) -> MavMessage:
    """PX4's CAMERA_IMAGE_CAPTURED (camera_feedback), level and facing north, 30.25 m
    above home; its relative_alt is the rangefinder's (-1 m: none)."""
    return mavlink2.MAVLink_camera_image_captured_message(
        42_000, 0, 0, lat, LON, 614_500, -1000, [1.0, 0.0, 0.0, 0.0], index, 1, b""
    )


def test_px4s_two_messages_of_a_shutter_are_one_camera_event_and_a_close_pair_two() -> None:
    """PX4 tells of each shutter with CAMERA_TRIGGER (where asked for) and
    CAMERA_IMAGE_CAPTURED, with one index: one event each, whichever comes first or alone;
    a lane end's two shutters a millisecond apart are two."""

    async def run() -> None:
        with ScriptedFlightController(autopilot=PX4) as fcu:
            async with agent_on(fcu) as agent:
                fcu.push(
                    mavlink2.MAVLink_global_position_int_message(
                        1000, LAT, LON, 614_500, 30_250, 0, 0, 0, 0
                    ),
                    mavlink2.MAVLink_camera_trigger_message(0, 0),
                    captured(0),
                    mavlink2.MAVLink_camera_trigger_message(0, 1),  # the lane end's pair
                    mavlink2.MAVLink_camera_trigger_message(0, 2),
                    captured(1),
                    captured(2),
                    captured(3, lat=LAT + 100),  # no CAMERA_TRIGGER: the link never asked
                )
                events = await agent.events(4)
                await agent.no_more_events()
        assert [e["kind"] for e in events] == ["camera"] * 4
        assert [e["photo"]["index"] for e in events] == [0, 1, 2, 3]
        assert events[3]["photo"] == {
            "index": 3,
            "lat": (LAT + 100) / 1e7,
            "lon": LON / 1e7,
            "alt_rel": 30.25,
        }

    asyncio.run(run())


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
