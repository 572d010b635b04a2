"""Which vehicle a simulator runs, and how long its flight controller takes to reboot."""

from __future__ import annotations

from simulator.config import SimulatorConfig
from simulator.copter import Copter
from simulator.personality import personality_for
from simulator.rover import Rover
from simulator.vehicle import Vehicle

# Wall seconds a rebooting flight controller says nothing, like a board restarting: long
# enough for a GCS to notice the silence (the agent gives up on a link after 3 s).
REBOOT_SILENCE_S = 4.0


def build_vehicle(config: SimulatorConfig) -> Vehicle:
    """The vehicle ``config`` describes, at its home, seeded by its system id."""
    if config.frame == "rover":
        return Rover(config.home, system_id=config.system_id, seed=config.system_id)
    return Copter(
        config.home,
        system_id=config.system_id,
        seed=config.system_id,
        personality=personality_for(config.autopilot),
    )
