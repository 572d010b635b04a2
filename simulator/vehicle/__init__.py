"""What every simulated vehicle shares, whatever it is and whichever autopilot it plays.

Sim time in fixed physics steps, the GPS and battery, home, the stored mission and how a
mission is walked through, the parameters, the camera, STATUSTEXTs and events, and what
a reboot keeps. `Copter` and `Rover` add their autopilot's rules and their motion. Pure
logic, no I/O and no wall clock: time moves only through `advance`/`advance_to`.
"""

from simulator.vehicle.events import Event, ItemReached, PhotoTaken, StatusText
from simulator.vehicle.state import DT, EKF_GPS_DELAY_S, AutoPhase
from simulator.vehicle.vehicle import Vehicle

__all__ = [
    "DT",
    "EKF_GPS_DELAY_S",
    "AutoPhase",
    "Event",
    "ItemReached",
    "PhotoTaken",
    "StatusText",
    "Vehicle",
]
