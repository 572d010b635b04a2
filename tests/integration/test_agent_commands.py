"""The agent's command exchange against a scripted flight controller over real TCP.

`ScriptedFlightController` (tests/support/mavlink_peer.py) is a MAVLink peer that sends
heartbeats and answers each command as the test scripts it: MAV_RESULT_IN_PROGRESS acks
with progress and then a final ACK, an ACK that never ends, a silent refusal. The
agent's `CommandExecutor` runs in-process with short timeouts, over its real `FcuLink`;
one case goes the whole way through the hub's REST API and an agent process.
"""

from __future__ import annotations

import subprocess
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import pytest
from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from protocol.messages import (
    ChangeSpeedCommand,
    Command,
    CommandOutcome,
    DisarmCommand,
    MissionItem,
    MissionUploadCommand,
    RebootCommand,
    SetHomeCommand,
    TakeoffCommand,
)
from tests.conftest import hub_settings
from tests.support.api import api_client
from tests.support.executors import with_executor
from tests.support.hub_server import running_hub
from tests.support.mavlink_peer import HOME_ALT_MSL, Answer, Script, ScriptedFlightController
from tests.support.processes import agent_process
from tests.support.watcher import FleetWatcher, connected
from vehicle_agents.control.executor import CommandExecutor
from vehicle_agents.fcu.messages import MavMessage

pytestmark = pytest.mark.integration

IN_PROGRESS = mavlink2.MAV_RESULT_IN_PROGRESS
ACCEPTED = mavlink2.MAV_RESULT_ACCEPTED


def execute(fcu: ScriptedFlightController, command: Command) -> CommandOutcome:
    async def body(executor: CommandExecutor) -> CommandOutcome:
        # the link is up once telemetry flows; commands are refused on a link that is down
        while executor.link.latest.get("HOME_POSITION") is None:
            await executor.link.wait_for(lambda m: m.get_type() == "HOME_POSITION", 5)
        return await executor.execute(command)

    return with_executor(fcu, body)


def in_progress_then(final: int, count: int = 3) -> Script:
    def script(_message: MavMessage) -> list[Answer]:
        steps = [
            Answer(0.1 * i, IN_PROGRESS, progress=100 * i // (count + 1)) for i in range(count)
        ]
        return [*steps, Answer(0.1 * count, final, progress=100)]

    return script


# -- MAV_RESULT_IN_PROGRESS -----------------------------------------------------------------


def test_in_progress_stops_retries_and_the_final_ack_is_reported() -> None:
    speed = mavlink2.MAV_CMD_DO_CHANGE_SPEED
    with ScriptedFlightController() as fcu:
        # each IN_PROGRESS comes later than one attempt's wait: only a retry would resend
        fcu.scripts[speed] = lambda _m: [
            Answer(0.1, IN_PROGRESS, progress=10),
            Answer(0.7, IN_PROGRESS, progress=60),
            Answer(1.3, ACCEPTED, progress=100),
        ]
        outcome = execute(fcu, ChangeSpeedCommand(speed=3.0))
        assert outcome.status == "accepted", outcome
        assert outcome.result == "MAV_RESULT_ACCEPTED"
        assert len(fcu.commands(speed)) == 1, "no retry once the autopilot has the command"


def test_a_command_that_stays_in_progress_times_out_saying_so() -> None:
    speed = mavlink2.MAV_CMD_DO_CHANGE_SPEED
    with ScriptedFlightController() as fcu:
        fcu.scripts[speed] = lambda _m: [Answer(0.05 + 0.4 * i, IN_PROGRESS, 40) for i in range(20)]
        started = time.monotonic()
        outcome = execute(fcu, ChangeSpeedCommand(speed=3.0))
        elapsed = time.monotonic() - started
    assert outcome.status == "timeout"
    assert outcome.result == "MAV_RESULT_IN_PROGRESS"
    assert "in progress (40%)" in outcome.message
    assert "no final COMMAND_ACK within 1.5 s" in outcome.message
    assert elapsed < 10, "bounded by the in-progress timeout, however many acks arrive"
    assert len(fcu.commands(speed)) == 1


def test_in_progress_then_refused_carries_the_reason() -> None:
    reboot = mavlink2.MAV_CMD_PREFLIGHT_REBOOT_SHUTDOWN
    with ScriptedFlightController() as fcu:
        fcu.scripts[reboot] = lambda _m: [
            Answer(0.05, IN_PROGRESS),
            Answer(0.2, None, text="Reboot rejected, ESC cal on reboot"),
            Answer(0.3, mavlink2.MAV_RESULT_FAILED),
        ]
        outcome = execute(fcu, RebootCommand())
    assert outcome.status == "refused"
    assert outcome.message == (
        "MAV_CMD_PREFLIGHT_REBOOT_SHUTDOWN: MAV_RESULT_FAILED (Reboot rejected, ESC cal on reboot)"
    )


# -- refusals the autopilot does not explain ------------------------------------------------


def refuse(_message: MavMessage) -> list[Answer]:
    return [Answer(0.0, mavlink2.MAV_RESULT_FAILED)]


def test_a_silent_refusal_of_a_disarm_in_flight_is_explained() -> None:
    arm_disarm = mavlink2.MAV_CMD_COMPONENT_ARM_DISARM
    with ScriptedFlightController(armed=True, in_air=True) as fcu:
        fcu.scripts[arm_disarm] = refuse
        outcome = execute(fcu, DisarmCommand())
        [sent] = fcu.commands(arm_disarm)
    assert (sent.param1, sent.param2) == (0, 0)
    assert outcome.status == "refused"
    assert "no reason from the autopilot" in outcome.message
    assert "in the air" in outcome.message
    assert "forced disarm" in outcome.message


def test_force_disarm_sends_the_magic_number() -> None:
    arm_disarm = mavlink2.MAV_CMD_COMPONENT_ARM_DISARM
    with ScriptedFlightController(armed=True, in_air=True) as fcu:
        fcu.scripts[arm_disarm] = lambda _m: [Answer(0.0, ACCEPTED)]
        assert execute(fcu, DisarmCommand(force=True)).status == "accepted"
        [sent] = fcu.commands(arm_disarm)
    assert (sent.param1, sent.param2) == (0, 21196)


def test_a_silent_refusal_to_reboot_while_armed_is_explained() -> None:
    reboot = mavlink2.MAV_CMD_PREFLIGHT_REBOOT_SHUTDOWN
    with ScriptedFlightController(armed=True) as fcu:
        fcu.scripts[reboot] = refuse
        outcome = execute(fcu, RebootCommand())
        [sent] = fcu.commands(reboot)
    assert sent.param1 == 1
    assert outcome.message.endswith(
        "(no reason from the autopilot; the vehicle is armed, and autopilots refuse to "
        "reboot while armed)"
    )


# -- what goes on the wire ------------------------------------------------------------------


def test_set_home_to_a_point_goes_as_command_int_at_full_precision() -> None:
    set_home = mavlink2.MAV_CMD_DO_SET_HOME
    with ScriptedFlightController() as fcu:
        fcu.scripts[set_home] = lambda _m: [Answer(0.0, ACCEPTED)]
        command = SetHomeCommand(use_current=False, lat=-35.3632611, lon=149.1652377, alt_msl=590)
        assert execute(fcu, command).status == "accepted"
        [sent] = fcu.commands(set_home)
    assert sent.get_type() == "COMMAND_INT"
    assert sent.frame == mavlink2.MAV_FRAME_GLOBAL  # altitude above mean sea level
    assert (sent.x, sent.y, sent.z) == (-353632611, 1491652377, 590)
    assert sent.param1 == 0


def test_px4_takeoff_arms_then_asks_for_an_altitude_above_sea_level() -> None:
    arm_disarm, takeoff = mavlink2.MAV_CMD_COMPONENT_ARM_DISARM, mavlink2.MAV_CMD_NAV_TAKEOFF
    with ScriptedFlightController(autopilot=mavlink2.MAV_AUTOPILOT_PX4) as fcu:
        fcu.scripts[arm_disarm] = lambda _m: [Answer(0.0, ACCEPTED)]
        fcu.scripts[takeoff] = lambda _m: [Answer(0.0, ACCEPTED)]
        assert execute(fcu, TakeoffCommand(altitude=12)).status == "accepted"
        [sent] = fcu.commands(takeoff)
        assert fcu.commands(mavlink2.MAV_CMD_DO_SET_MODE) == []  # PX4 switches by itself
    assert sent.param7 == pytest.approx(HOME_ALT_MSL + 12)


def test_a_rover_is_not_asked_to_take_off() -> None:
    with ScriptedFlightController(mav_type=mavlink2.MAV_TYPE_GROUND_ROVER) as fcu:
        outcome = execute(fcu, TakeoffCommand(altitude=10))
        assert fcu.commands(mavlink2.MAV_CMD_NAV_TAKEOFF) == []
    assert outcome.status == "refused"
    assert outcome.message == "takeoff: a rover does not take off"


def test_a_bad_mission_item_is_refused_before_anything_is_sent() -> None:
    speed = mavlink2.MAV_CMD_DO_CHANGE_SPEED
    items = [
        MissionItem(command=mavlink2.MAV_CMD_NAV_TAKEOFF, alt=10),
        MissionItem(command=mavlink2.MAV_CMD_NAV_WAYPOINT, alt=10),  # no position
        MissionItem(command=mavlink2.MAV_CMD_NAV_LOITER_TIME, param1=-5, lat=-35.36, lon=149.16),
    ]

    async def upload_then_probe(executor: CommandExecutor) -> CommandOutcome:
        while executor.link.latest.get("HOME_POSITION") is None:
            await executor.link.wait_for(lambda m: m.get_type() == "HOME_POSITION", 5)
        outcome = await executor.execute(MissionUploadCommand(items=items))
        # a command sent after the refusal: once it arrives, anything before it has too
        executor.link.send_command_long(speed, 0, [1, 3, -1])
        return outcome

    with ScriptedFlightController() as fcu:
        outcome = with_executor(fcu, upload_then_probe)
        fcu.wait_for_command(speed, 5)
        kinds = fcu.kinds()
    assert outcome.status == "refused"
    assert outcome.message.startswith("mission refused, nothing sent to the vehicle: ")
    assert "item 2 (NAV_WAYPOINT): latitude and longitude are 0, 0" in outcome.message
    assert "item 3 (NAV_LOITER_TIME): loiter time -5 s is negative" in outcome.message
    assert "item 1" not in outcome.message
    assert not [kind for kind in kinds if kind.startswith("MISSION_")]


# -- the whole way: REST, hub, agent process, flight controller --------------------------------


@pytest.fixture
def scripted_agent(
    hub: str, enrol: Callable[[str], str]
) -> Iterator[tuple[ScriptedFlightController, subprocess.Popen[bytes]]]:
    with (
        ScriptedFlightController() as fcu,
        agent_process(hub, enrol("scripted"), "scripted", fcu.port) as agent,
    ):
        yield fcu, agent


def test_in_progress_through_the_hub(
    hub: str,
    admin_token: str,
    scripted_agent: tuple[ScriptedFlightController, subprocess.Popen[bytes]],
) -> None:
    fcu, _agent = scripted_agent
    fcu.scripts[mavlink2.MAV_CMD_DO_CHANGE_SPEED] = in_progress_then(ACCEPTED)
    with FleetWatcher(hub, admin_token) as watcher:
        watcher.wait_until(connected("scripted"), 30, "the agent to connect")
    with api_client(hub, admin_token) as api:
        response = api.post(
            "/api/v1/vehicles/scripted/commands",
            json={"name": "change_speed", "speed": 4, "speed_type": "ground"},
        )
    assert response.status_code == 200, response.text
    outcome: dict[str, Any] = response.json()["outcome"]
    assert outcome["status"] == "accepted"
    assert outcome["result"] == "MAV_RESULT_ACCEPTED"
    [sent] = fcu.commands(mavlink2.MAV_CMD_DO_CHANGE_SPEED)
    assert (sent.param1, sent.param2) == (1, 4)


@pytest.fixture
def hub(tmp_path: Path) -> Iterator[str]:
    """This module's hub gives agents 2 s per command, so a deadline is quick to reach."""
    with running_hub(hub_settings(tmp_path, command_timeout_s=2.0)) as base_url:
        yield base_url


def test_the_agent_stops_a_command_at_the_hubs_deadline(
    hub: str,
    admin_token: str,
    scripted_agent: tuple[ScriptedFlightController, subprocess.Popen[bytes]],
) -> None:
    fcu, _agent = scripted_agent
    # in progress for far longer than the hub allows (the agent's own wait is 10 s)
    fcu.scripts[mavlink2.MAV_CMD_DO_CHANGE_SPEED] = lambda _m: [
        Answer(0.05 + 0.3 * i, IN_PROGRESS, 10) for i in range(40)
    ]
    with FleetWatcher(hub, admin_token) as watcher:
        watcher.wait_until(connected("scripted"), 30, "the agent to connect")
    with api_client(hub, admin_token) as api:
        started = time.monotonic()
        response = api.post(
            "/api/v1/vehicles/scripted/commands", json={"name": "change_speed", "speed": 4}
        )
        elapsed = time.monotonic() - started
    assert response.status_code == 504, response.text
    assert "not finished within 1.5 s; the agent stopped it there" in response.text
    assert elapsed < 4, "the agent's answer, not the hub's own give-up"
