"""Another hub's vehicles in this hub's registry (several hubs): mirrored from the
shared bus, reached through a remote channel, never over this hub's own agent."""

from __future__ import annotations

from backend.fleet.commands import AgentChannel
from backend.fleet.registry import FleetRegistry
from protocol.messages import Message, VehicleState, VehicleSummary
from tests.support.hellos import agent_hello


class _Remote(AgentChannel):
    remote = True

    def __init__(self) -> None:
        super().__init__(self._nowhere)

    async def _nowhere(self, message: Message) -> None:
        raise RuntimeError("a test channel")


def _summary(connected: bool, mode: str = "LOITER") -> VehicleSummary:
    return VehicleSummary(
        id="v",
        autopilot="ardupilot",
        vehicle_type="multirotor",
        modes=["GUIDED", "LOITER"],
        connected=connected,
        last_seen=10.0,
        state=VehicleState(mode=mode),
    )


def test_another_hubs_vehicle_is_known_and_reached_through_one_remote_channel() -> None:
    registry = FleetRegistry()
    made: list[_Remote] = []

    def remote() -> _Remote:
        made.append(_Remote())
        return made[-1]

    record = registry.mirror(_summary(True), remote)
    assert record is not None
    assert record.connected
    assert record.channel is made[0]
    assert record.modes == ["GUIDED", "LOITER"]
    registry.mirror(_summary(True, mode="GUIDED"), remote)
    assert len(made) == 1, "one channel per vehicle, not one per update"
    state = registry.get("v").state
    assert state is not None
    assert state.mode == "GUIDED"
    # Its hub says it is gone: offline here too.
    registry.mirror(_summary(False), remote)
    assert not registry.get("v").connected


def test_this_hubs_own_agent_is_never_overridden_by_another_hubs_word() -> None:
    registry = FleetRegistry()
    own = AgentChannel(_Remote()._nowhere)
    registry.connect(agent_hello("v"), own)
    # A late word from the hub the agent just left must not take the vehicle away.
    assert registry.mirror(_summary(False), _Remote) is None
    assert registry.get("v").channel is own
    assert registry.mirror(_summary(True), _Remote) is None
    assert registry.get("v").channel is own
