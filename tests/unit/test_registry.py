from __future__ import annotations

import pytest

from backend.errors import VehicleNotFound
from backend.fleet.registry import FleetRegistry
from protocol.messages import Telemetry, VehicleState
from tests.helpers import agent_hello


def _sample(seq: int, time: float, alt: float) -> Telemetry:
    return Telemetry(seq=seq, time=time, state=VehicleState(alt_rel=alt))


def test_duplicates_are_dropped_per_stream() -> None:
    registry = FleetRegistry()
    registry.connect(agent_hello("v", stream_id="s1"))
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
