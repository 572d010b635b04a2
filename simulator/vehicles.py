"""Which vehicle a simulator runs, and how long its flight controller takes to reboot."""

from __future__ import annotations

from simulator.config import SimulatorConfig
from simulator.copter import Copter
from simulator.params.table import SetOutcome
from simulator.personality import personality_for
from simulator.rover import Rover
from simulator.vehicle import Vehicle

# Wall seconds a rebooting flight controller says nothing, like a board restarting: long
# enough for a GCS to notice the silence (the agent gives up on a link after 3 s).
REBOOT_SILENCE_S = 4.0


def build_vehicle(config: SimulatorConfig) -> Vehicle:
    """The vehicle ``config`` describes, at its home, seeded by its system id, with its
    boot parameters set; raises ValueError for one it cannot take."""
    vehicle: Vehicle
    if config.frame == "rover":
        vehicle = Rover(config.home, system_id=config.system_id, seed=config.system_id)
    else:
        vehicle = Copter(
            config.home,
            system_id=config.system_id,
            seed=config.system_id,
            personality=personality_for(config.autopilot),
        )
    for name, value in config.params:
        # Through the same check as a GCS's PARAM_SET: a typo must not start a vehicle
        # that quietly lacks the setting it was given.
        outcome = vehicle.set_param(name, value)
        if outcome is SetOutcome.UNKNOWN:
            raise ValueError(f"--param {name}: this vehicle has no such parameter")
        if outcome is not SetOutcome.STORED:
            raise ValueError(f"--param {name}={value:g}: out of its range")
    return vehicle
