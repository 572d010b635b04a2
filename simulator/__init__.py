"""A simulated ArduCopter multirotor that speaks MAVLink 2, used in place of SITL.

Run it with ``python -m simulator`` or ``gcs sim``; embed it with
`SimulatorServer`; drive the pure flight logic directly with `Copter`.
"""

from common.geodesy import GeoPoint, LocalFrame
from simulator.cli import main, run
from simulator.clock import Clock, ManualClock, SimClock
from simulator.config import DEFAULT_HOME, ListenAddress, SimulatorConfig
from simulator.copter import Copter
from simulator.mavconst import CopterMode, MavResult
from simulator.params.values import CopterParams
from simulator.server import SimulatorServer
from simulator.vehicle import DT, StatusText

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
