"""AUTO: flying the stored mission's nav commands (ModeAuto)."""

from __future__ import annotations

import math

from simulator.copter.state import CopterState
from simulator.mavconst import MavCmd, Severity
from simulator.vehicle import DT, AutoPhase
from simulator.vehicle.physics import Setpoint
from simulator.vehicle.stored_mission import MissionItem

TAKEOFF_DONE_M = 0.1  # a take-off is complete this close to its altitude
WAYPOINT_ALT_TOLERANCE_M = 1.0


class Auto(CopterState):
    """The mission's nav commands, step by step."""

    def _mission_starts_with_takeoff(self) -> bool:
        seq = self._first_nav_seq()
        return seq is not None and self.mission[seq].command == MavCmd.NAV_TAKEOFF

    def _auto_complete(self) -> None:
        """ModeAuto::exit_mission: hold where it is (disarms if on the ground)."""
        self._auto_item = None
        self._auto_phase = AutoPhase.DONE
        self._hold_ne = self.body.stopping_point(self.params.wpnav_accel)
        self._hold_alt = self._stopping_alt()
        self._say(Severity.INFO, "Mission complete")
        if self.armed and self.land_complete:
            self._disarm()

    def _start_nav(self, item: MissionItem) -> None:
        self._auto_item = item
        self._auto_hold_s = 0.0
        match item.command:
            case MavCmd.NAV_TAKEOFF:
                self._auto_phase = AutoPhase.TAKEOFF
                alt = max(self._relative_to_origin(self._item_alt(item)), self.body.alt)
                if self.land_complete:
                    self._takeoff_alt = alt if alt > 0.0 else None
                else:
                    self._hold_ne = (self.body.north, self.body.east)
                    self._hold_alt = alt
            case MavCmd.NAV_RETURN_TO_LAUNCH:
                self._auto_phase = AutoPhase.RTL
                self._start_rtl(self.body.stopping_point(self.params.wpnav_accel))
            case MavCmd.NAV_LAND:
                self._hold_ne = self._item_ne(item)
                self._hold_alt = self.body.alt
                self._land_ne = self._hold_ne
                self._auto_phase = AutoPhase.FLY if item.has_position else AutoPhase.LAND
            case _:  # NAV_WAYPOINT, NAV_LOITER_TIME
                self._hold_ne = self._item_ne(item)
                alt = self._item_alt(item)
                if alt != 0.0 or item.has_position:
                    self._hold_alt = self._relative_to_origin(alt)
                else:
                    self._hold_alt = self.body.alt
                self._auto_phase = AutoPhase.FLY

    def _auto_setpoint(self) -> Setpoint:
        """ModeAuto::run for the nav command in progress."""
        p = self.params
        face = p.wp_yaw_behavior != 0
        item = self._auto_item
        phase = self._auto_phase
        if phase is AutoPhase.TAKEOFF and not self._taking_off:
            if abs(self.body.alt - self._hold_alt) < TAKEOFF_DONE_M:
                if (
                    item is not None
                    and item.has_position
                    and self.personality.takeoff_flies_to_position
                ):
                    # PX4: the climb is done; now to the take-off's position, level
                    self._hold_ne = self._item_ne(item)
                    self._auto_phase = AutoPhase.FLY
                    return self._auto_setpoint()
                self._nav_done()
                return self._auto_setpoint_after_switch()
        elif phase is AutoPhase.FLY and item is not None:
            distance = math.dist(self._hold_ne, (self.body.north, self.body.east))
            radius = item.param2 if item.command == MavCmd.NAV_WAYPOINT else 0.0
            radius = radius if radius > 0.0 else p.wpnav_radius
            level = abs(self.body.alt - self._hold_alt) < WAYPOINT_ALT_TOLERANCE_M
            if distance <= radius and level:
                if item.command == MavCmd.NAV_LAND:
                    self._auto_phase = AutoPhase.LAND
                    return self._landing_setpoint(self._land_ne)
                if item.command == MavCmd.NAV_TAKEOFF:
                    self._nav_done()  # a take-off's position reached (PX4): done
                    return self._auto_setpoint_after_switch()
                if item.command == MavCmd.NAV_WAYPOINT:
                    self._say(Severity.INFO, f"Reached command #{item.seq}")
                self._auto_phase = AutoPhase.HOLD
                self._auto_hold_s = max(0.0, item.param1)
                return self._auto_setpoint_after_switch()
        elif phase is AutoPhase.HOLD:
            self._auto_hold_s -= DT
            if self._auto_hold_s <= 1e-9:
                self._nav_done()
                return self._auto_setpoint_after_switch()
        elif phase is AutoPhase.LAND:
            return self._landing_setpoint(self._land_ne)
        elif phase is AutoPhase.RTL:
            return self._rtl_setpoint()
        return Setpoint(
            self._hold_ne,
            self._hold_alt,
            speed_xy=self._speed_xy,
            speed_up=self._speed_up,
            speed_down=self._speed_down,
            face_travel=face and phase is AutoPhase.FLY,
        )

    def _auto_setpoint_after_switch(self) -> Setpoint:
        """The setpoint of whatever follows a completed step, without re-checking it
        (a waypoint with no delay is left in the step it is reached)."""
        if self._auto_phase is AutoPhase.HOLD and self._auto_hold_s > 1e-9:
            return Setpoint(self._hold_ne, self._hold_alt, face_travel=False)
        if self._auto_phase is AutoPhase.HOLD:
            self._nav_done()
        if self._auto_phase in (AutoPhase.LAND, AutoPhase.RTL):
            return self._auto_setpoint()
        return Setpoint(
            self._hold_ne,
            self._hold_alt,
            speed_xy=self._speed_xy,
            speed_up=self._speed_up,
            speed_down=self._speed_down,
            face_travel=self.params.wp_yaw_behavior != 0 and self._auto_phase is AutoPhase.FLY,
        )
