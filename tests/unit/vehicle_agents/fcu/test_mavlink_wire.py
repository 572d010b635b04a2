"""Every protocol field that ends up in a MAVLink field is bounded by that field's wire
type, read from pymavlink's own message definitions; and the agent names a field that
does not fit instead of letting pymavlink's packing error escape."""

from __future__ import annotations

import math
from types import SimpleNamespace
from typing import Any, cast

import pytest
from pydantic import BaseModel, ValidationError
from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from protocol.mavlink_wire import DEGE7, FLOAT32_MAX, WIRE_RANGES, out_of_range
from protocol.messages import (
    ChangeSpeedCommand,
    GotoCommand,
    MissionItem,
    MissionSetCurrentCommand,
    ParamSetCommand,
    SetHomeCommand,
    TakeoffCommand,
)
from vehicle_agents.fcu.link import FcuLink
from vehicle_agents.fcu.messages import wire_problems
from vehicle_agents.fcu.missions import MissionClient, wire_seq

# (protocol model, its field) -> (the MAVLink message that carries it, that field, the
# scale applied on the way). What the agent's commands.py, params.py and missions.py send.
CARRIED: list[tuple[type[BaseModel], str, type[Any], str, float]] = [
    (ParamSetCommand, "value", mavlink2.MAVLink_param_set_message, "param_value", 1),
    *(
        (MissionItem, f"param{n}", mavlink2.MAVLink_mission_item_int_message, f"param{n}", 1)
        for n in range(1, 5)
    ),
    (MissionItem, "command", mavlink2.MAVLink_mission_item_int_message, "command", 1),
    (MissionItem, "frame", mavlink2.MAVLink_mission_item_int_message, "frame", 1),
    (MissionItem, "lat", mavlink2.MAVLink_mission_item_int_message, "x", DEGE7),
    (MissionItem, "lon", mavlink2.MAVLink_mission_item_int_message, "y", DEGE7),
    (MissionItem, "alt", mavlink2.MAVLink_mission_item_int_message, "z", 1),
    (GotoCommand, "lat", mavlink2.MAVLink_command_int_message, "x", DEGE7),
    (GotoCommand, "lon", mavlink2.MAVLink_command_int_message, "y", DEGE7),
    (GotoCommand, "altitude", mavlink2.MAVLink_command_int_message, "z", 1),
    (SetHomeCommand, "lat", mavlink2.MAVLink_command_int_message, "x", DEGE7),
    (SetHomeCommand, "lon", mavlink2.MAVLink_command_int_message, "y", DEGE7),
    (SetHomeCommand, "alt_msl", mavlink2.MAVLink_command_int_message, "z", 1),
    (TakeoffCommand, "altitude", mavlink2.MAVLink_command_long_message, "param7", 1),
    (ChangeSpeedCommand, "speed", mavlink2.MAVLink_command_long_message, "param2", 1),
    (MissionSetCurrentCommand, "seq", mavlink2.MAVLink_mission_set_current_message, "seq", 1),
]


def _bounds(model: type[BaseModel], name: str) -> tuple[float, float]:
    schema = model.model_json_schema()["properties"][name]
    schema = next((s for s in schema.get("anyOf", []) if s.get("type") != "null"), schema)
    low = schema.get("minimum", schema.get("exclusiveMinimum", -math.inf))
    high = schema.get("maximum", schema.get("exclusiveMaximum", math.inf))
    return low, high


@pytest.mark.parametrize(
    ("model", "name", "message", "wire_name", "scale"),
    CARRIED,
    ids=[f"{m.__name__}.{n}" for m, n, *_ in CARRIED],
)
def test_protocol_bounds_fit_the_wire_type(
    model: type[BaseModel], name: str, message: type[Any], wire_name: str, scale: float
) -> None:
    c_type = dict(zip(message.fieldnames, message.fieldtypes, strict=True))[wire_name]
    wire_low, wire_high = WIRE_RANGES[c_type]
    low, high = _bounds(model, name)
    why = (
        f"{model.__name__}.{name} allows {low}..{high}, but {message.msgname}.{wire_name} "
        f"is a {c_type} ({wire_low}..{wire_high}) after scaling by {scale}"
    )
    assert wire_low <= low * scale, why
    assert high * scale <= wire_high, why


@pytest.mark.parametrize("value", [1e300, -1e300, math.nan, math.inf, FLOAT32_MAX * 1.0001])
def test_values_a_float32_cannot_hold_are_refused_naming_the_field(value: float) -> None:
    with pytest.raises(ValidationError) as refused:
        ParamSetCommand(param="WPNAV_SPEED", value=value)
    assert refused.value.errors()[0]["loc"] == ("value",)
    with pytest.raises(ValidationError) as refused:
        MissionItem(command=16, lat=1, lon=1, param3=value)
    assert refused.value.errors()[0]["loc"] == ("param3",)


def test_the_extremes_the_protocol_allows_pack_into_mavlink() -> None:
    extreme = MissionItem(
        command=65535,
        frame=21,
        param1=FLOAT32_MAX,
        param2=-FLOAT32_MAX,
        param3=FLOAT32_MAX,
        param4=-FLOAT32_MAX,
        lat=-90,
        lon=180,
        alt=10000,
    )
    mav = mavlink2.MAVLink(None)
    client = MissionClient(cast(FcuLink, SimpleNamespace(target_system=1, target_component=1)))
    message = client._item_message(wire_seq(2000, "ardupilot"), extreme)
    assert wire_problems(message) == []
    assert message.pack(mav)


def test_the_agent_names_the_field_a_value_does_not_fit() -> None:
    message = mavlink2.MAVLink_mission_item_int_message(
        1, 1, 70000, 6, 16, 0, 1, 1e300, 0, 0, 0, 2**31, 0, 0.0, 0
    )
    assert wire_problems(message) == [
        "seq: 70000 does not fit a uint16_t (0..65535)",
        "param1: 1e+300 does not fit a float32 (at most ±3.402823e+38)",
        "x: 2147483648 does not fit a int32_t (-2147483648..2147483647)",
    ]
    assert out_of_range([("values", "uint8_t", [1, 256])]) == [
        "values: 256 does not fit a uint8_t (0..255)"
    ]
    # float32 carries NaN (MAVLink's "unset"), a char field has no numeric range
    assert out_of_range([("p", "float", math.nan), ("id", "char", b"WPNAV_SPEED")]) == []
