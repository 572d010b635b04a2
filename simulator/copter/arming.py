"""Arming and disarming (AP_Arming_Copter), the land detector and the auto-disarm."""

from __future__ import annotations

from simulator.copter.state import POSITION_MODES, CopterState
from simulator.mavconst import CopterMode, MavResult, Severity
from simulator.vehicle import DT, AutoPhase
from simulator.vehicle.physics import Setpoint


class Arming(CopterState):
    """The arming checks, disarming, and the land detector that disarms."""

    def arm(self, force: bool = False) -> MavResult:
        """MAV_CMD_COMPONENT_ARM_DISARM param1=1; ``force`` is param2=2989."""
        if self.armed:
            return MavResult.ACCEPTED
        needs_position = self.mode in POSITION_MODES
        if force:
            # only the mandatory checks run
            if needs_position and not self.position_ok:
                self._say(Severity.CRITICAL, "Arm: Need Position Estimate")
                return self.personality.declined
        else:
            if needs_position and not self.position_ok:
                # a bad fix, or a good one the EKF does not use yet
                text = "GPS 1: Bad fix" if self.gps_fix_type < 3 else "Need Position Estimate"
                self._say(Severity.CRITICAL, f"Arm: {text}")
                return self.personality.declined
            if not self.personality.allows_arming(self.mode):
                self._say(Severity.CRITICAL, f"Arm: {self.mode.name} mode not armable")
                return self.personality.declined
        self.armed = True
        self._armed_at = self.time_s
        self._disarm_timer_s = 0.0
        self._takeoff_alt = None
        if self.body.on_ground:
            self.land_complete = True
            self._home_on_arming()
        self._say(Severity.INFO, "Arming motors")
        return MavResult.ACCEPTED

    def disarm(self, force: bool = False) -> MavResult:
        """MAV_CMD_COMPONENT_ARM_DISARM param1=0; ``force`` is param2=21196. ArduCopter
        declines a GCS disarm in the air without a word (AP_Arming_Copter::disarm)."""
        if not self.armed:
            return MavResult.ACCEPTED
        if not force and not self.land_complete:
            text = self.personality.disarm_declined_text()
            if text is not None:
                self._say(Severity.CRITICAL, text)
            return self.personality.declined
        self._disarm()
        return MavResult.ACCEPTED

    def _disarm(self) -> None:
        self.armed = False
        self.land_complete = True
        self._takeoff_alt = None
        self._taking_off = False
        # AP_Arming_Copter::disarm resets the mission (mode_auto.mission.reset()): the next
        # flight, and a mission uploaded meanwhile, start again from the first command.
        self.mission_current = 0
        self._say(Severity.INFO, "Disarming motors")

    def _detect_landing(self, setpoint: Setpoint | None) -> None:
        """Touchdown once resting on the ground, not climbing, for LAND_DETECTOR_TRIGGER."""
        if not self.flying:
            self._on_ground_s = 0.0
            return
        resting = self.body.on_ground and self.body.climb_rate <= 0.0 and setpoint is not None
        if not resting:
            self._on_ground_s = 0.0
            return
        self._on_ground_s += DT
        if self._on_ground_s + 1e-9 < self.params.land_detector_trigger:
            return
        self.land_complete = True
        self._taking_off = False
        self._disarm_timer_s = 0.0
        if self._landing() or self.mode is CopterMode.LAND or self.mode is CopterMode.RTL:
            if self.mode is CopterMode.AUTO and self._auto_phase in (
                AutoPhase.LAND,
                AutoPhase.RTL,
            ):
                self._nav_done()  # the landing completes; so does the mission
            if self.armed:
                self._disarm()

    def _check_auto_disarm(self) -> None:
        """Copter::auto_disarm_check: landed and armed for DISARM_DELAY."""
        if not (self.armed and self.land_complete) or self.params.disarm_delay <= 0.0:
            self._disarm_timer_s = 0.0
            return
        self._disarm_timer_s += DT
        if self._disarm_timer_s + 1e-9 >= self.params.disarm_delay:
            self._disarm()
