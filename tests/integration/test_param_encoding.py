"""Integer parameters read and written through the agent, as each autopilot encodes them.

PX4 copies integers bytewise into PARAM_VALUE's float and advertises
MAV_PROTOCOL_CAPABILITY_PARAM_ENCODE_BYTEWISE; ArduPilot casts them (PARAM_ENCODE_C_CAST).
The agent's executor runs over a real FcuLink to the simulator in each personality, and
what the simulated vehicle stores is checked, not only what the agent answers.
"""

from __future__ import annotations

import asyncio
from collections.abc import Awaitable, Callable
from typing import TypeVar

import pytest

from protocol.messages import (
    CommandOutcome,
    ParamGetCommand,
    ParamListCommand,
    ParamSetCommand,
)
from simulator.config import Autopilot
from tests.support.fcu import fcu_url, on_link, simulated
from vehicle_agents.control.executor import CommandExecutor
from vehicle_agents.fcu.param_encoding import ParamEncoding, decode, encode

pytestmark = pytest.mark.integration
T = TypeVar("T")

SYSID = 1  # the simulator's default system id


def run(
    autopilot: Autopilot, body: Callable[[CommandExecutor], Awaitable[T]]
) -> tuple[T, dict[str, float]]:
    """``body``'s result and the parameters the simulated vehicle holds afterwards."""
    with simulated(autopilot) as server:
        result = asyncio.run(on_link(fcu_url(server), body))
        table = server.copter.param_table
        stored = {name: float(table.get(name) or 0.0) for name in table.names()}
    return result, stored


def test_px4_integers_are_read_and_written_bytewise() -> None:
    writes = {
        "SDLOG_UTC_OFFSET": 60,  # the field trial's write, which stored 1114636288
        "COM_FLTMODE1": -1,  # a NaN if read as a float
        "CAL_ACC0_ID": 2_139_095_041,  # a signalling NaN's bit pattern
        "NAV_DLL_ACT": 2,
        "MPC_XY_CRUISE": 7.5,  # a float stays a float
    }

    async def body(executor: CommandExecutor) -> list[CommandOutcome]:
        outcomes = [await executor.execute(ParamListCommand())]
        for name, value in writes.items():
            outcomes.append(await executor.execute(ParamSetCommand(param=name, value=value)))
        outcomes.append(await executor.execute(ParamGetCommand(param="CAL_ACC0_ID")))
        outcomes.append(await executor.execute(ParamSetCommand(param="MAV_SYS_ID", value=1.5)))
        return outcomes

    (listing, *sets, reread, fraction), stored = run("px4", body)
    assert listing.status == "accepted", listing
    assert listing.values is not None
    assert listing.values["MAV_SYS_ID"] == SYSID  # not 1.4e-45
    assert listing.values["COM_FLTMODE1"] == -1  # not NaN
    assert listing.values["CAL_ACC0_ID"] == 1310988
    assert listing.values["MIS_TAKEOFF_ALT"] == 2.5
    for (name, value), outcome in zip(writes.items(), sets, strict=True):
        assert outcome.status == "accepted", outcome
        assert outcome.values == {name: value}, "the decoded echo confirms the write"
        assert stored[name] == value, f"{name}: the vehicle holds what was asked for"
    assert reread.values == {"CAL_ACC0_ID": 2_139_095_041}
    assert fraction.status == "refused"
    assert fraction.message == "MAV_SYS_ID: 1.5 is not an integer, and the parameter is one"
    assert stored["MAV_SYS_ID"] == SYSID


def test_ardupilot_integers_are_cast_to_float() -> None:
    writes = {"SERIAL2_PROTOCOL": -1, "BATT_CAPACITY": 1_000_000, "RTL_ALT": 2500}

    async def body(executor: CommandExecutor) -> list[CommandOutcome]:
        outcomes = [await executor.execute(ParamListCommand())]
        for name, value in writes.items():
            outcomes.append(await executor.execute(ParamSetCommand(param=name, value=value)))
        return outcomes

    (listing, *sets), stored = run("ardupilot", body)
    assert listing.status == "accepted", listing
    assert listing.values is not None
    assert listing.values["SYSID_THISMAV"] == SYSID
    assert listing.values["SERIAL2_PROTOCOL"] == 2
    assert listing.values["RTL_ALT"] == 1500
    for (name, value), outcome in zip(writes.items(), sets, strict=True):
        assert outcome.status == "accepted", outcome
        assert outcome.values == {name: value}
        assert stored[name] == value


@pytest.mark.parametrize("encoding", ["bytewise", "c_cast"])
@pytest.mark.parametrize(
    ("value", "param_type"),
    [
        (-1, 6),
        (60, 6),
        (2_147_483_647, 6),
        (-2_147_483_648, 6),
        (-4_194_305, 6),
        (-128, 2),
        (65535, 3),
        (0.1, 9),
        (-3.4e38, 9),
    ],
)
def test_encode_then_decode_gives_the_value_back(
    value: float, param_type: int, encoding: ParamEncoding
) -> None:
    """Every integer type's extremes, exact bytewise; C cast within a float32."""
    back = decode(encode(value, param_type, encoding), param_type, encoding)
    assert back == pytest.approx(value, rel=1e-7)
    if encoding == "bytewise" and param_type != 9:
        assert back == value
