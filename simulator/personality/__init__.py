"""Which autopilot the simulated multirotor plays: how it names its modes on the wire and
answers what it declines.

The flight behaviour is the copter's own (ArduCopter's rules, see `simulator.copter`); a
personality maps its flight modes to and from the autopilot's encoding, as a GCS sees it:

* ArduCopter: HEARTBEAT.custom_mode is the mode number; DO_SET_MODE param2 is that number;
  a declined command is MAV_RESULT_FAILED.
* PX4 (commander/px4_custom_mode.h, mavlink_messages.cpp, Commander.cpp): custom_mode
  packs main mode << 16 and sub mode << 24; DO_SET_MODE takes them apart in param2 and
  param3; a declined mode change, arming or disarming is TEMPORARILY_REJECTED and a
  reboot while armed DENIED; NAV_TAKEOFF's altitude is above mean sea level. Its modes
  land on the copter's behaviours: MANUAL, STABILIZED and ALTCTL hold altitude with the
  sticks centred (STABILIZE here), POSCTL and AUTO.LOITER ("Hold") hold position
  (LOITER), AUTO.MISSION flies the mission (AUTO), AUTO.RTL and AUTO.LAND are RTL and
  LAND, and a reposition is flown in Hold, as PX4's navigator does. Switched to Mission
  it does not arm itself (Commander arms on request only); armed in Mission on the
  ground with a mission it takes off on the take-off item, and a take-off item with a
  position is flown to once the climb is done. A reposition or a
  set-home sent as COMMAND_INT is taken only in MAV_FRAME_GLOBAL_INT (MAV_RESULT 9,
  COMMAND_UNSUPPORTED_MAV_FRAME, for any other frame). Its parameters have PX4's names
  and types, integers sent bytewise (`params.px4`, `params.wire`). Its camera tells of
  a shutter with CAMERA_IMAGE_CAPTURED, and with CAMERA_TRIGGER where a GCS asked for it,
  never with ArduPilot's CAMERA_FEEDBACK.

Manual control: ArduCopter flies MANUAL_CONTROL from SYSID_MYGCS only, as an RC override,
and without one its LOITER flies SITL's transmitter (throttle at its minimum: it sinks).
PX4 takes it from any sender when COM_RC_IN_MODE lets MAVLink input in, refuses POSCTL in
the air until some has come, and when it stops flies NAV_RCL_ACT after COM_RC_LOSS_T +
COM_FAIL_ACT_T unless COM_RCL_EXCEPT exempts the mode (bit 0 Mission, bit 1 Hold).
"""

from __future__ import annotations

from simulator.personality.ardupilot import ArduCopterPersonality
from simulator.personality.base import Personality
from simulator.personality.px4 import Px4Personality


def personality_for(autopilot: str) -> Personality:
    if autopilot == "px4":
        return Px4Personality()
    return ArduCopterPersonality()
