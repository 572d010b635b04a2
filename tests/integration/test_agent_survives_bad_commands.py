"""No command from the hub, however malformed, ends the agent.

A scripted hub (a real WebSocket server) sends a real `gcs agent` process commands that
are out of every MAVLink field's range, not numbers, unknown, or not commands at all.
Each one that carries a request id is answered as failed, and afterwards the agent is
still running and still carries a good command to its flight controller (a scripted
MAVLink peer). The executor's own guard is checked in-process too, with commands that
skip the protocol's validation, as a bug in the agent would.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from protocol.messages import (
    ChangeSpeedCommand,
    CommandOutcome,
    GotoCommand,
    ManualApplied,
    ManualFrame,
)
from tests.support.executors import with_executor
from tests.support.mavlink_peer import Answer, ScriptedFlightController
from tests.support.processes import agent_process
from tests.support.scripted_hub import ScriptedHub, _command
from tests.support.waiting import poll_until_async
from vehicle_agents.control.executor import CommandExecutor
from vehicle_agents.control.manual import ManualPilot

pytestmark = pytest.mark.integration

VEHICLE = "bounds_1"


def _manual(seq: int, **axes: object) -> str:
    return json.dumps(
        {"type": "manual", "seq": seq, "axes": {"x": 0, "y": 0, "z": 500, "r": 0, **axes}}
    )


NAN, INF = float("nan"), float("inf")
WAYPOINT = {"command": 16, "lat": -35.36, "lon": 149.16, "alt": 20}
MALFORMED: dict[str, object] = {
    "param_set 1e300": {"name": "param_set", "param": "WPNAV_SPEED", "value": 1e300},
    "param_set NaN": {"name": "param_set", "param": "WPNAV_SPEED", "value": NAN},
    "param_set -Infinity": {"name": "param_set", "param": "WPNAV_SPEED", "value": -INF},
    "mission param1 1e300": {"name": "mission_upload", "items": [{**WAYPOINT, "param1": 1e300}]},
    "mission param4 NaN": {"name": "mission_upload", "items": [{**WAYPOINT, "param4": NAN}]},
    "mission lat 1e300": {"name": "mission_upload", "items": [{**WAYPOINT, "lat": 1e300}]},
    "mission command 70000": {"name": "mission_upload", "items": [{**WAYPOINT, "command": 70000}]},
    "set_current 70000": {"name": "mission_set_current", "seq": 70000},
    "set_current 1e300": {"name": "mission_set_current", "seq": 1e300},
    "goto NaN": {"name": "goto", "lat": NAN, "lon": 149.0, "altitude": 10},
    "goto lon 1e300": {"name": "goto", "lat": -35.0, "lon": 1e300, "altitude": 10},
    "takeoff Infinity": {"name": "takeoff", "altitude": INF},
    "change_speed 1e300": {"name": "change_speed", "speed": 1e300},
    "set_home alt 1e300": {
        "name": "set_home",
        "use_current": False,
        "lat": -35.0,
        "lon": 149.0,
        "alt_msl": 1e300,
    },
    "unknown command": {"name": "self_destruct"},
    "not an object": 12,
    "set_mode with a list": {"name": "set_mode", "mode": ["GUIDED"] * 1000},
}


def test_malformed_commands_are_answered_as_failed_and_the_agent_goes_on(
    tmp_path: Path,
) -> None:
    change_speed = mavlink2.MAV_CMD_DO_CHANGE_SPEED
    with (
        ScriptedFlightController() as fcu,
        ScriptedHub() as hub,
        agent_process(hub.url, "t" * 32, VEHICLE, fcu.port, tmp_path) as agent,
    ):
        fcu.scripts[change_speed] = lambda _m: [Answer(0.0, mavlink2.MAV_RESULT_ACCEPTED)]
        connection = hub.connections.get(timeout=30)
        for number, (case, command) in enumerate(MALFORMED.items()):
            outcome = hub.answer_to(connection, _command(f"bad-{number}", command))
            assert outcome["status"] == "failed", (case, outcome)
            assert "refused by the agent" in outcome["message"], (case, outcome)
        for number, timeout_s in enumerate([1e300, -1, NAN, "soon"]):
            frame = _command(f"deadline-{number}", {"name": "hold"}, timeout_s)
            assert hub.answer_to(connection, frame)["status"] == "failed", timeout_s
        # no request id to answer: read past, as any unusable frame
        for frame in ["[" * 30_000, "{", '{"type": "command"}', json.dumps({"type": 5})]:
            connection.send(frame)
        # stick input no MANUAL_CONTROL field can hold (int16 axes, uint16 buttons)
        for axis in ("x", "y", "z", "r", "buttons"):
            for bad in (1e300, NAN, 70000):
                connection.send(_manual(1, **{axis: bad}))

        good = _command("good", {"name": "change_speed", "speed": 3.0})
        assert hub.answer_to(connection, good)["status"] == "accepted"
        assert agent.poll() is None, "the agent is still running"
        assert hub.connections.empty(), "and it never had to reconnect"
        sent = {m.get_type() for m in fcu.received}
        assert not sent & {"PARAM_SET", "MISSION_COUNT", "MANUAL_CONTROL"}, sent


def test_stick_input_while_the_flight_controller_is_away_is_dropped_not_raised() -> None:
    """A pilot's 25 Hz stream goes on while the flight controller's link is down (a USB
    cable out, the autopilot rebooting): the frames cannot be flown and are dropped. Raised
    instead, each would end the agent's hub session, and the hub link would flap at the
    pilot's rate. (The lease is opened as ``start`` leaves it once a real autopilot has
    passed its checks; the scripted one answers no parameters.)"""
    fcu = ScriptedFlightController()

    async def body(executor: CommandExecutor) -> list[ManualApplied | None]:
        link = executor.link
        pilot = ManualPilot(link, executor, lambda *_: None)
        pilot.active = True
        first = pilot.on_frame(ManualFrame.model_validate_json(_manual(1, x=300)))
        # Flown: the flight controller has it (its reader is a thread of its own)...
        await poll_until_async(lambda: "MANUAL_CONTROL" in fcu.kinds(), 10, "the first frame")
        fcu.__exit__(None, None, None)  # ...then it goes
        await poll_until_async(lambda: not link.connected, 10, "the link to go down")
        return [first] + [
            pilot.on_frame(ManualFrame.model_validate_json(_manual(seq, x=300)))
            for seq in range(2, 27)
        ]

    with fcu:
        answers = with_executor(fcu, body)
    assert "MANUAL_CONTROL" in fcu.kinds(), "the first frame was flown"
    assert answers[1:] == [None] * 25


def test_the_executor_answers_a_value_that_slipped_past_validation_as_failed() -> None:
    """The agent's second line: a value no MAVLink field can hold fails the command,
    naming the field, instead of raising out of the executor."""

    async def both(executor: CommandExecutor) -> tuple[CommandOutcome, CommandOutcome]:
        speed = await executor.execute(ChangeSpeedCommand.model_construct(speed=1e300))
        goto = GotoCommand.model_construct(lat=1e300, lon=0.0, altitude=10.0)
        return speed, await executor.execute(goto)

    with ScriptedFlightController() as fcu:
        speed, goto = with_executor(fcu, both)
        sent = fcu.kinds()
    assert speed.status == "failed"
    assert "COMMAND_LONG not sent: param2: 1e+300 does not fit a float32" in speed.message
    assert goto.status == "failed"
    assert "COMMAND_INT not sent: x:" in goto.message
    assert "COMMAND_LONG" not in sent
    assert "COMMAND_INT" not in sent
