"""What the copter does on its own when something fails (Copter::failsafe_*)."""

from __future__ import annotations

from simulator.copter.state import CopterState
from simulator.mavconst import CopterMode, MavResult, Severity


class Failsafes(CopterState):
    """The battery failsafe; GPS and link failsafes land here too."""

    def _check_battery(self) -> None:
        """Copter::handle_battery_failsafe once the monitor reports the pack low."""
        p = self.params
        if not self._battery_low() or p.batt_fs_low_act == 0:
            return
        if self.land_complete:
            # should_disarm_on_failsafe: on the ground the action is to disarm
            self._disarm()
            return
        if self.mode is CopterMode.LAND:
            return
        if self.mode is CopterMode.RTL:
            return
        if p.batt_fs_low_act == 2 and self.set_mode(CopterMode.RTL) is MavResult.ACCEPTED:
            return
        self.set_mode(CopterMode.LAND)  # action 1, or RTL without a position

    def _check_manual_loss(self) -> None:
        """PX4's manual-control-loss failsafe, once manual input has come and stopped."""
        if self._sticks is None or not self.armed:
            return
        silent = self.time_s - self._sticks_at
        action = self.personality.manual_loss_action(self.mode, silent, self.param_table)
        if action is None:
            return
        self._sticks = None  # acted on: new input arms it again
        self._say(Severity.CRITICAL, "Failsafe activated: manual control lost")
        self.set_mode(action)
