"""A stored mission (AP_Mission's view of it): items in MISSION_ITEM_INT terms.

Item 0 is home, as in ArduPilot: whatever a GCS uploads as item 0 is stored, but reading
it back always gives the current home. Pure data, no I/O.
"""

from __future__ import annotations

from dataclasses import dataclass

from simulator.mavconst import MavCmd, MavFrame

# Navigation commands the simulated AUTO mode flies, and the "do" commands it runs.
NAV_COMMANDS = frozenset(
    {
        MavCmd.NAV_WAYPOINT,
        MavCmd.NAV_LOITER_TIME,
        MavCmd.NAV_RETURN_TO_LAUNCH,
        MavCmd.NAV_LAND,
        MavCmd.NAV_TAKEOFF,
    }
)
DO_COMMANDS = frozenset(
    {MavCmd.DO_CHANGE_SPEED, MavCmd.DO_SET_CAM_TRIGG_DIST, MavCmd.DO_DIGICAM_CONTROL}
)
SUPPORTED_COMMANDS = NAV_COMMANDS | DO_COMMANDS
LOCATION_COMMANDS = NAV_COMMANDS - {MavCmd.NAV_RETURN_TO_LAUNCH}

# Frames a mission item may use: altitudes relative to home (terrain is flat here), or
# above mean sea level; "do" commands carry no position and may say MISSION.
RELATIVE_FRAMES = frozenset(
    {
        MavFrame.GLOBAL_RELATIVE_ALT,
        MavFrame.GLOBAL_RELATIVE_ALT_INT,
        MavFrame.GLOBAL_TERRAIN_ALT,
        MavFrame.GLOBAL_TERRAIN_ALT_INT,
    }
)
ABSOLUTE_FRAMES = frozenset({MavFrame.GLOBAL, MavFrame.GLOBAL_INT})
SUPPORTED_FRAMES = RELATIVE_FRAMES | ABSOLUTE_FRAMES | {MavFrame.MISSION}

MAX_ITEMS = 700  # ArduPilot's mission size on a board with a 16 kB storage area


@dataclass(frozen=True)
class MissionItem:
    """One MISSION_ITEM_INT; ``x``/``y`` are degrees * 1e7 (or an integer param5/6)."""

    seq: int
    frame: int
    command: int
    param1: float = 0.0
    param2: float = 0.0
    param3: float = 0.0
    param4: float = 0.0
    x: int = 0
    y: int = 0
    z: float = 0.0
    autocontinue: int = 1

    @property
    def is_nav(self) -> bool:
        return self.command in NAV_COMMANDS

    @property
    def has_position(self) -> bool:
        return self.x != 0 or self.y != 0


def check_item(item: MissionItem) -> str | None:
    """Why ArduPilot would refuse to store ``item`` ("unsupported", "frame"), or None."""
    if item.seq == 0:
        return None  # home: replaced by the vehicle's own
    if item.command not in SUPPORTED_COMMANDS:
        return "unsupported"
    if item.frame not in SUPPORTED_FRAMES:
        return "frame"
    if item.command in LOCATION_COMMANDS and item.frame == MavFrame.MISSION:
        # AP_Mission checks the frame only of commands that store a location
        # (stored_in_location): an RTL in MAV_FRAME_MISSION, as QGC writes it, is fine.
        return "frame"
    return None


# Autopilots store whether an altitude is relative, not which message form named it:
# ArduPilot's AP_Mission gives back GLOBAL, GLOBAL_RELATIVE_ALT or GLOBAL_TERRAIN_ALT for an
# item sent in their "_INT" forms; PX4 gives back the "_INT" forms to MISSION_REQUEST_INT.
_STORED_FRAME: dict[int, int] = {
    MavFrame.GLOBAL_INT: MavFrame.GLOBAL,
    MavFrame.GLOBAL_RELATIVE_ALT_INT: MavFrame.GLOBAL_RELATIVE_ALT,
    MavFrame.GLOBAL_TERRAIN_ALT_INT: MavFrame.GLOBAL_TERRAIN_ALT,
}
_INT_FRAME: dict[int, int] = {stored: sent for sent, stored in _STORED_FRAME.items()}


def stored_frame(frame: int) -> int:
    return int(_STORED_FRAME.get(frame, frame))  # IntEnum keys hash as their numbers


def px4_download_frame(frame: int) -> int:
    return int(_INT_FRAME.get(frame, frame))


# Item 0 as ArduPilot stores it: home, whose position the vehicle keeps itself.
HOME_PLACEHOLDER = MissionItem(seq=0, frame=MavFrame.GLOBAL, command=MavCmd.NAV_WAYPOINT)
