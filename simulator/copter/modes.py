"""Mode changes as Copter::set_mode makes them, from any of the ways a GCS asks."""

from __future__ import annotations

from simulator.copter.state import BRAKE_DECEL, POSITION_MODES, CopterState
from simulator.mavconst import SUPPORTED_MODES, CopterMode, MavResult, Severity
from simulator.personality.base import PX4_TAKEOFF_ALT_M, Declined, ModeRequest
from simulator.vehicle import AutoPhase


class Modes(CopterState):
    """Which mode may be entered now, and what entering it sets up."""

    def set_mode(self, number: int) -> MavResult:
        """Copter::set_mode for a GCS request."""
        if number == self.mode:
            return MavResult.ACCEPTED
        mode = self._requested_mode(number, CopterMode, SUPPORTED_MODES)
        if mode is None:
            return MavResult.FAILED
        ignore_checks = not self.armed  # any mode may be selected while disarmed
        if not ignore_checks and mode in POSITION_MODES and not self.position_ok:
            self._say(Severity.WARNING, f"Mode change to {mode.name} failed: requires position")
            return MavResult.FAILED
        if mode is CopterMode.AUTO and not ignore_checks:
            if self.mission_count == 0:
                # ModeAuto::init: no mission present
                self._say(Severity.WARNING, "Mode change to AUTO failed: init failed")
                return MavResult.FAILED
            if self.land_complete and not self._mission_starts_with_takeoff():
                self._say(Severity.CRITICAL, "Auto: Missing Takeoff Cmd")
                self._say(Severity.WARNING, "Mode change to AUTO failed: init failed")
                return MavResult.FAILED
        self._enter_mode(mode)
        return MavResult.ACCEPTED

    def request_mode(self, base_mode: int, custom_mode: int, custom_sub_mode: int) -> MavResult:
        return self._requested(self.personality.decode(base_mode, custom_mode, custom_sub_mode))

    def request_mode_encoded(self, base_mode: int, custom_mode: int) -> MavResult:
        return self._requested(self.personality.decode_encoded(base_mode, custom_mode))

    def _requested(self, request: ModeRequest | Declined) -> MavResult:
        if isinstance(request, Declined):
            if request.text is not None:
                self._say(Severity.CRITICAL, request.text)
            return request.result
        if request.takeoff:
            return self._autopilot_takeoff(PX4_TAKEOFF_ALT_M)
        if (
            self.armed
            and self.personality.needs_manual_input(request, self.param_table)
            and not self._manual_input_fresh()
        ):
            self._say(Severity.CRITICAL, "Switching to Position is currently not possible")
            self._say(Severity.CRITICAL, "No manual control input")
            return self.personality.declined
        result = self.set_mode(request.mode)
        if result is not MavResult.ACCEPTED:
            return self.personality.declined
        self.personality.selected(request)
        return result

    def _manual_input_fresh(self) -> bool:
        """Manual input has come within COM_RC_LOSS_T (0.5 s, PX4's default)."""
        timeout = self.param_table.get("COM_RC_LOSS_T") or 0.5
        return self._sticks is not None and self.time_s - self._sticks_at <= timeout

    def _mode_command(self, mode: CopterMode) -> MavResult:
        result = self.set_mode(mode)
        return result if result is MavResult.ACCEPTED else self.personality.declined

    def nav_land(self) -> MavResult:
        return self._mode_command(CopterMode.LAND)

    def return_to_launch(self) -> MavResult:
        return self._mode_command(CopterMode.RTL)

    def _enter_mode(self, mode: CopterMode) -> None:
        p = self.params
        # leaving a mode cancels any take-off in progress
        self._takeoff_alt = None
        self._taking_off = False
        self.mode = mode
        self._auto_phase = AutoPhase.IDLE
        stop_ne = self.body.stopping_point(p.wpnav_accel)
        if mode in (CopterMode.STABILIZE, CopterMode.LOITER, CopterMode.AUTO):
            self._hold_ne = stop_ne
            self._hold_alt = self._stopping_alt()
            if mode is CopterMode.AUTO:
                self._speed_xy, self._speed_up, self._speed_down = (
                    p.wpnav_speed,
                    p.wpnav_speed_up,
                    p.wpnav_speed_dn,
                )
                if self.armed and self.mission_count > 0:
                    self._auto_begin()  # ModeAuto::init: mission.start_or_resume
        elif mode is CopterMode.GUIDED:
            self._guided_hold()
        elif mode is CopterMode.BRAKE:
            # ModeBrake::init: stop at BRAKE_MODE_DECEL_RATE, hold the altitude reached
            self._hold_ne = self.body.stopping_point(BRAKE_DECEL)
            self._hold_alt = self._stopping_alt(BRAKE_DECEL)
        elif mode is CopterMode.LAND:
            self._land_ne = stop_ne
        elif mode is CopterMode.RTL:
            self._start_rtl(stop_ne)
