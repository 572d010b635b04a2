"""The simulated multirotor: ArduCopter's arming rules, flight modes and navigation.

Pure logic, no I/O and no wall clock: time moves only through `advance`, in fixed
physics steps of `DT` sim seconds, so a run is the same whatever the speed-up and however
the elapsed time is sliced. Commands return a `MavResult`; anything ArduCopter would say
in a STATUSTEXT is queued and collected with `drain_texts`. A `Personality` decides which
autopilot it shows itself as on the wire (ArduCopter, or PX4's mode encoding).

Behaviour follows ArduCopter 4.x (ArduCopter/mode*.cpp, AP_Arming_Copter.cpp):

* arming is refused without a 3D fix in modes that need a position, and in RTL, LAND,
  AUTO and BRAKE ("mode not armable"); param2=2989 forces it past everything but the
  position check;
* a GCS disarm is refused while flying unless forced (param2=21196);
* after arming the motors idle for ARMING_DELAY plus the spool-up time before a take-off;
* on the ground and armed for DISARM_DELAY it disarms itself; LAND and RTL disarm as soon
  as the land detector (1 s resting on the ground) reports touchdown, BRAKE at once;
* BRAKE stops as hard as BRAKE_MODE_DECEL_RATE allows and holds there;
* home moves to the vehicle's position when it arms, unless a GCS has set (and so
  locked) it with MAV_CMD_DO_SET_HOME.
"""

from simulator.copter.copter import Copter
from simulator.copter.state import RtlStage

__all__ = ["Copter", "RtlStage"]
