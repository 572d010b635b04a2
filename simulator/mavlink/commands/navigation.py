"""Where the vehicle goes and where home is: DO_REPOSITION, SET_POSITION_TARGET_GLOBAL_INT
and DO_SET_HOME, with the frames their altitudes are given in."""

from __future__ import annotations

import math
from typing import Any

from simulator.mavconst import (
    DO_REPOSITION_FLAGS_CHANGE_MODE,
    POSITION_TARGET_IGNORE_POSITION,
    POSITION_TARGET_IGNORE_VELOCITY,
    POSITION_TARGET_IGNORE_YAW,
    MavCmd,
    MavFrame,
    MavResult,
)
from simulator.mavlink.commands.base import Command, HandlerBase, as_int, log

_GLOBAL_FRAMES = frozenset({MavFrame.GLOBAL, MavFrame.GLOBAL_INT})
_RELATIVE_FRAMES = frozenset(
    {
        MavFrame.GLOBAL_RELATIVE_ALT,
        MavFrame.GLOBAL_RELATIVE_ALT_INT,
        # flat simulated world: terrain altitude is altitude above home
        MavFrame.GLOBAL_TERRAIN_ALT,
        MavFrame.GLOBAL_TERRAIN_ALT_INT,
    }
)

# Commands whose COMMAND_INT frame says where the position is (PX4 checks it).
POSITION_COMMANDS = frozenset({MavCmd.DO_REPOSITION, MavCmd.DO_SET_HOME})


class Navigation(HandlerBase):
    def _relative_alt(self, frame: int, alt: float) -> float | None:
        if frame in _RELATIVE_FRAMES:
            return alt
        if frame in _GLOBAL_FRAMES:
            return alt - self.copter.home.alt
        return None

    def _reposition(self, cmd: Command) -> MavResult:
        """GCS_MAVLINK_Copter::handle_command_int_do_reposition."""
        copter = self.copter
        change_mode = bool(as_int(cmd.param2) & DO_REPOSITION_FLAGS_CHANGE_MODE)
        if not copter.in_guided and not change_mode:
            return MavResult.DENIED
        here = copter.position()
        lat, lon = (here.lat, here.lon) if cmd.x_unset else (cmd.x, cmd.y)
        if not (-90.0 <= lat <= 90.0 and -180.0 <= lon <= 180.0):
            return MavResult.DENIED
        alt = copter.relative_alt if math.isnan(cmd.z) else self._relative_alt(cmd.frame, cmd.z)
        if alt is None:
            return MavResult.DENIED
        if not copter.in_guided and copter.enter_guided() is not MavResult.ACCEPTED:
            return MavResult.FAILED
        if cmd.param1 > 0.0:
            copter.change_speed(0, cmd.param1)
        return copter.guided_goto(lat, lon, alt)

    def _position_target(self, msg: Any) -> None:
        """SET_POSITION_TARGET_GLOBAL_INT in GUIDED, ignored otherwise
        (GCS_MAVLINK_Copter::handle_message_set_position_target_global_int): a position, a
        velocity, or both. As there, any set bit of a group ignores the whole group, and
        an acceleration-only target is not flown."""
        copter = self.copter
        if not copter.in_guided:
            return
        mask = int(msg.type_mask)
        pos_ignore = bool(mask & POSITION_TARGET_IGNORE_POSITION)
        vel_ignore = bool(mask & POSITION_TARGET_IGNORE_VELOCITY)
        velocity = (float(msg.vx), float(msg.vy), float(msg.vz))
        yaw = None if mask & POSITION_TARGET_IGNORE_YAW else float(msg.yaw)
        if pos_ignore:
            if vel_ignore:
                log.debug("acceleration-only position targets are not simulated")
            elif copter.guided_posvel(None, velocity, yaw) is not MavResult.ACCEPTED:
                copter.guided_hold()
            return
        lat, lon = int(msg.lat_int) / 1e7, int(msg.lon_int) / 1e7
        alt = self._relative_alt(int(msg.coordinate_frame), float(msg.alt))
        if alt is None or not (-90.0 <= lat <= 90.0 and -180.0 <= lon <= 180.0):
            copter.guided_hold()  # ArduCopter re-initialises guided on a bad target
            return
        if vel_ignore:
            copter.guided_goto(lat, lon, alt)
        elif copter.guided_posvel((lat, lon, alt), velocity, yaw) is not MavResult.ACCEPTED:
            copter.guided_hold()

    def _set_home(self, cmd: Command) -> MavResult:
        """GCS_MAVLINK::handle_command_do_set_home: param1=1, or no position given, is
        the current location; otherwise the point, its altitude above mean sea level."""
        if cmd.param1 == 1.0 or cmd.x_unset or (cmd.x == 0.0 and cmd.y == 0.0):
            return self.copter.set_home_here()
        if cmd.frame in _GLOBAL_FRAMES:
            alt_msl = cmd.z
        elif cmd.frame in _RELATIVE_FRAMES:
            alt_msl = cmd.z + self.copter.home.alt
        else:
            return MavResult.DENIED
        return self.copter.set_home_to(cmd.x, cmd.y, alt_msl)
