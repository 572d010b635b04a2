from __future__ import annotations

import json

import pytest

from protocol.messages import (
    CommandRequest,
    ProtocolError,
    TakeoffCommand,
    Telemetry,
    VehicleState,
    agent_to_hub,
    command_adapter,
    encode,
    hub_to_agent,
    json_schema,
)


def test_round_trip_keeps_every_field() -> None:
    telemetry = Telemetry(seq=7, time=12.5, state=VehicleState(lat=1.5, armed=True, mode="LAND"))
    assert agent_to_hub.decode(encode(telemetry)) == telemetry
    request = CommandRequest(request_id="r", command=TakeoffCommand(altitude=12), timeout_s=5)
    assert hub_to_agent.decode(encode(request)) == request


@pytest.mark.parametrize(
    ("frame", "code", "names"),
    [
        ("{nope", "bad_frame", "not valid JSON"),
        ("[1, 2]", "invalid_message", "'type' field"),
        ('{"type": "teleport"}', "invalid_message", "teleport"),
        ('{"type": "telemetry", "seq": -1, "time": 0, "state": {}}', "invalid_message", "seq"),
        (
            '{"type": "telemetry", "seq": 1, "time": 0, "state": {"armed": "maybe"}}',
            "invalid_message",
            "state.armed",
        ),
        (
            '{"type": "telemetry", "seq": 1, "time": 0, "state": {}, "extra": 1}',
            "invalid_message",
            "extra",
        ),
    ],
)
def test_bad_frames_raise_errors_that_name_the_problem(frame: str, code: str, names: str) -> None:
    with pytest.raises(ProtocolError) as raised:
        agent_to_hub.decode(frame)
    assert raised.value.code == code
    assert names in raised.value.message


def test_commands_are_validated_by_name() -> None:
    assert command_adapter.validate_python({"name": "land"}).name == "land"
    with pytest.raises(ValueError, match="altitude"):
        command_adapter.validate_python({"name": "takeoff", "altitude": -3})
    with pytest.raises(ValueError, match="lat"):
        command_adapter.validate_python({"name": "goto", "lat": 91, "lon": 0, "altitude": 10})


def test_schema_bundle_is_json_and_versioned() -> None:
    bundle = json.loads(json.dumps(json_schema()))
    assert bundle["protocol"] == 1
    assert {"agent_to_hub", "hub_to_agent", "client_to_hub", "hub_to_client"} <= set(bundle)
