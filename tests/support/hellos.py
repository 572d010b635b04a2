"""The first message of a scripted agent."""

from __future__ import annotations

from collections.abc import Sequence

from protocol.messages import PROTOCOL_VERSION, Hello


def agent_hello(
    vehicle_id: str = "v1",
    *,
    stream_id: str = "s",
    system_id: int = 1,
    modes: Sequence[str] = ("GUIDED", "LAND", "LOITER"),
) -> Hello:
    """The first message of an agent for an ArduPilot multirotor, for tests that play one."""
    return Hello(
        protocol=PROTOCOL_VERSION,
        vehicle_id=vehicle_id,
        autopilot="ardupilot",
        vehicle_type="multirotor",
        system_id=system_id,
        modes=list(modes),
        agent_version="test",
        stream_id=stream_id,
    )
