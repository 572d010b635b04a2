"""Arming, modes and reboots: COMPONENT_ARM_DISARM, DO_SET_MODE, SET_MODE and
PREFLIGHT_REBOOT_SHUTDOWN."""

from __future__ import annotations

from typing import Any

from simulator.mavconst import FORCE_ARM_MAGIC, FORCE_DISARM_MAGIC, FORCE_REBOOT_MAGIC, MavResult
from simulator.mavlink.commands.base import Command, HandlerBase, Reply, as_int

MSG_ID_SET_MODE = 11  # ArduPilot acknowledges SET_MODE with a COMMAND_ACK for "command" 11


class ArmingAndModes(HandlerBase):
    def _arm_disarm(self, cmd: Command) -> MavResult:
        """MAV_CMD_COMPONENT_ARM_DISARM: param1 1 arms, 0 disarms; param2 forces."""
        if cmd.param1 == 1.0:
            return self.copter.arm(force=cmd.param2 == FORCE_ARM_MAGIC)
        if cmd.param1 == 0.0:
            return self.copter.disarm(force=cmd.param2 == FORCE_DISARM_MAGIC)
        return MavResult.UNSUPPORTED

    def _do_set_mode(self, cmd: Command) -> MavResult:
        return self.copter.request_mode(as_int(cmd.param1), as_int(cmd.param2), as_int(cmd.param3))

    def _set_mode_message(self, msg: Any) -> list[Reply]:
        """SET_MODE, acknowledged with a COMMAND_ACK as ArduPilot does."""
        result = self.copter.request_mode_encoded(int(msg.base_mode), int(msg.custom_mode))
        return self._finish(MSG_ID_SET_MODE, result, msg)

    def _reboot(self, cmd: Command) -> MavResult:
        return self.copter.request_reboot(cmd.param1, force=cmd.raw_y == FORCE_REBOOT_MAGIC)
