from __future__ import annotations

import asyncio

import pytest

from backend.errors import VehicleNotFound, VehicleOffline
from backend.fleet.commands import AgentChannel, CommandDispatcher
from backend.fleet.registry import FleetRegistry
from protocol.messages import ArmCommand, CommandRequest, Telemetry, VehicleState
from tests.support.hellos import agent_hello


def _sample(seq: int, time: float, alt: float) -> Telemetry:
    return Telemetry(seq=seq, time=time, state=VehicleState(alt_rel=alt))


def test_duplicates_are_dropped_per_stream() -> None:
    registry = FleetRegistry()
    registry.connect(agent_hello("v", stream_id="s1"), _channel([]))
    assert registry.apply("v", "s1", _sample(0, 1.0, 1.0))
    assert registry.apply("v", "s1", _sample(1, 2.0, 2.0))
    assert not registry.apply("v", "s1", _sample(1, 2.0, 2.0))
    assert not registry.apply("v", "s1", _sample(0, 1.0, 1.0))
    # A restarted agent starts a new stream at 0: not a duplicate.
    assert registry.apply("v", "s2", _sample(0, 3.0, 3.0))
    record = registry.get("v")
    assert record.state is not None
    assert record.state.alt_rel == 3.0


def test_unknown_vehicle_raises() -> None:
    with pytest.raises(VehicleNotFound, match="ghost"):
        FleetRegistry().get("ghost")


def _channel(sent: list[CommandRequest]) -> AgentChannel:
    async def send(message: CommandRequest) -> None:
        sent.append(message)
        raise OSError("test channel: nothing answers")

    return AgentChannel(send)


def test_the_channel_is_the_one_record_of_connected() -> None:
    asyncio.run(_the_channel_is_the_one_record_of_connected())


async def _the_channel_is_the_one_record_of_connected() -> None:
    registry = FleetRegistry()
    dispatcher = CommandDispatcher(registry, timeout_s=1.0)
    first_sent: list[CommandRequest] = []
    second_sent: list[CommandRequest] = []
    first, second = _channel(first_sent), _channel(second_sent)
    registry.connect(agent_hello("v", stream_id="s1"), first)
    registry.connect(agent_hello("v", stream_id="s1"), second)  # a new agent takes the vehicle over
    # The superseded agent leaving does not take the vehicle offline ...
    assert registry.disconnect("v", first) is None
    assert registry.get("v").connected
    assert registry.get("v").summary().connected
    # ... and commands go to the agent that has it.
    with pytest.raises(VehicleOffline, match="connection closed"):
        await dispatcher.execute("v", ArmCommand())
    assert (len(first_sent), len(second_sent)) == (0, 1)
    offline = registry.disconnect("v", second)
    assert offline is registry.get("v")
    assert not offline.connected
    assert not offline.summary().connected
    with pytest.raises(VehicleOffline, match="not connected"):
        await dispatcher.execute("v", ArmCommand())


def test_samples_are_ordered_by_number_not_by_the_agent_s_clock() -> None:
    registry = FleetRegistry()
    registry.connect(agent_hello("v", stream_id="s1"), _channel([]))
    assert registry.apply("v", "s1", _sample(0, 5000.0, 1.0))
    # The agent's clock steps back an hour: the next sample is still the newest.
    assert registry.apply("v", "s1", _sample(1, 1400.0, 2.0))
    # A live state ahead of a replaying backlog: the backlog is only stored...
    assert registry.apply_live("v", 1500.0, VehicleState(alt_rel=9.0))
    assert not registry.apply("v", "s1", _sample(2, 1401.0, 3.0))
    # ...until a sample as recent arrives; from then on numbers order them again.
    assert registry.apply("v", "s1", _sample(3, 1500.5, 4.0))
    assert registry.apply("v", "s1", _sample(4, 1000.0, 5.0))
    state = registry.get("v").state
    assert state is not None
    assert state.alt_rel == 5.0
