"""A flight controller that accepts the link and says nothing."""

from __future__ import annotations

from tests.support.mavlink_peer import ScriptedFlightController
from vehicle_agents.fcu.messages import MavMessage


class SilentFlightController(ScriptedFlightController):
    """A real MAVLink peer on TCP that sends heartbeats and ignores every command (it has
    no scripts, so it answers none)."""

    def telemetry(self) -> list[MavMessage]:
        return [self.heartbeat()]  # a 5 Hz heartbeat is the whole behaviour
