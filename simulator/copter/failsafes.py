"""What the copter does on its own when something fails (Copter::failsafe_*)."""

from __future__ import annotations

from simulator.copter.state import CopterState
from simulator.mavconst import CopterMode, MavResult


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
