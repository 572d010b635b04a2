"""Flight-controller parameters that decide what a vehicle does when something goes wrong
(failsafes, the geofence, arming checks). Only an admin may change them; for anyone else
a write is refused with the reason. Pure data and one look-up, no I/O.

Names follow each autopilot's parameter reference (ArduPilot 4.x, PX4 1.14+); a pattern
is a shell-style glob over the whole name (``BATT*_FS_*`` covers every battery monitor).
"""

from __future__ import annotations

from dataclasses import dataclass
from fnmatch import fnmatchcase


@dataclass(frozen=True)
class CriticalGroup:
    what: str  # what these parameters protect, as the refusal says it
    patterns: tuple[str, ...]


ARDUPILOT: tuple[CriticalGroup, ...] = (
    # ARMING_SKIPCHK replaces ARMING_CHECK from 4.7; both are listed for older firmware.
    CriticalGroup("arming checks", ("ARMING_CHECK", "ARMING_SKIPCHK", "ARMING_REQUIRE")),
    CriticalGroup(
        "failsafes (radio, GCS, EKF, crash, dead reckoning)",
        ("FS_*", "THR_FAILSAFE", "THR_FS_VALUE", "AFS_*"),
    ),
    CriticalGroup("battery failsafe", ("BATT*_FS_*", "BATT*_LOW_*", "BATT*_CRT_*")),
    CriticalGroup("geofence", ("FENCE_*",)),
    # Whose heartbeats feed the GCS failsafe and who may send stick input (RC overrides,
    # MANUAL_CONTROL): SYSID_MYGCS, renamed MAV_GCS_SYSID in 4.7 with an upper bound
    # MAV_GCS_SYSID_HI. A wrong value lets another system fly it, or starves the failsafe.
    CriticalGroup(
        "the GCS's system id: whose heartbeats feed the GCS failsafe and who may fly it by hand",
        ("SYSID_MYGCS", "MAV_GCS_SYSID", "MAV_GCS_SYSID_HI"),
    ),
    # How long ArduPilot holds an RC override after the last one: 0 ignores overrides, and
    # -1 holds the last stick for ever, so a stopped stick stream would never let go.
    CriticalGroup(
        "how long a stick override holds once the stick stream stops",
        ("RC_OVERRIDE_TIME",),
    ),
)

PX4: tuple[CriticalGroup, ...] = (
    CriticalGroup(
        "failsafe actions (data link, RC, battery, ...)",
        (
            "COM_*_ACT",
            "COM_*_EXCEPT",
            "COM_DL_LOSS_T",
            "COM_RC_LOSS_T",
            "NAV_DLL_ACT",
            "NAV_RCL_ACT",
        ),
    ),
    CriticalGroup("arming checks", ("COM_ARM_*",)),
    CriticalGroup("circuit breakers (they switch safety checks off)", ("CBRK_*",)),
    CriticalGroup("battery failsafe", ("BAT_LOW_THR", "BAT_CRIT_THR", "BAT_EMERGEN_THR")),
    CriticalGroup("geofence", ("GF_*",)),
    CriticalGroup("failure detector", ("FD_*",)),
    # Which manual input PX4 takes: RC only (0), MAVLink only (1: the RC transmitter no
    # longer flies it), either (2, 3), or none (4: no manual input, so no RC-loss failsafe).
    CriticalGroup(
        "manual input source: the RC transmitter, MAVLink, or none",
        ("COM_RC_IN_MODE",),
    ),
)

BY_AUTOPILOT: dict[str, tuple[CriticalGroup, ...]] = {"ardupilot": ARDUPILOT, "px4": PX4}


def critical_reason(autopilot: str, param: str) -> str | None:
    """Why ``param`` is safety-critical on ``autopilot``, or None if it is not.

    An autopilot we do not know gets both lists: better an admin's extra step than a
    failsafe switched off by accident."""
    groups = BY_AUTOPILOT.get(autopilot, ARDUPILOT + PX4)
    name = param.upper()
    for group in groups:
        if any(fnmatchcase(name, pattern) for pattern in group.patterns):
            return group.what
    return None
