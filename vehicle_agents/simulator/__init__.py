"""A simulated ArduCopter multirotor that speaks MAVLink 2, used in place of SITL.

Run it with ``python -m vehicle_agents.simulator`` or ``gcs sim``; embed it with
`SimulatorServer`; drive the pure flight logic directly with `Copter`.
"""

from vehicle_agents.simulator.cli import main, run
from vehicle_agents.simulator.clock import Clock, ManualClock, SimClock
from vehicle_agents.simulator.config import DEFAULT_HOME, ListenAddress, SimulatorConfig
from vehicle_agents.simulator.copter import DT, Copter, StatusText
from vehicle_agents.simulator.geo import GeoPoint, LocalFrame
from vehicle_agents.simulator.mavconst import CopterMode, MavResult
from vehicle_agents.simulator.params import CopterParams
from vehicle_agents.simulator.server import SimulatorServer

__all__ = [
    "DEFAULT_HOME",
    "DT",
    "Clock",
    "Copter",
    "CopterMode",
    "CopterParams",
    "GeoPoint",
    "ListenAddress",
    "LocalFrame",
    "ManualClock",
    "MavResult",
    "SimClock",
    "SimulatorConfig",
    "SimulatorServer",
    "StatusText",
    "main",
    "run",
]
