"""GUIDED flight: take-offs, position targets and speeds from a GCS (ModeGuided)."""

from __future__ import annotations

import math

from simulator.copter.state import CopterState
from simulator.mavconst import CopterMode, MavFrame, MavResult
from simulator.params.values import CopterParams
from simulator.personality.base import PX4_TAKEOFF_ALT_M
from simulator.vehicle import DT
from simulator.vehicle.physics import Setpoint

# Modes that accept MAV_CMD_NAV_TAKEOFF on the ground (Mode::has_user_takeoff).
_USER_TAKEOFF = frozenset({CopterMode.GUIDED, CopterMode.LOITER})
_RELATIVE_TAKEOFF_FRAMES = frozenset(
    {MavFrame.GLOBAL_RELATIVE_ALT, MavFrame.GLOBAL_RELATIVE_ALT_INT}
)


class Guided(CopterState):
    """Take-off, position targets and speed changes."""

    def _guided_hold(self) -> None:
        """ModeGuided::init: reset speeds, hold at the stopping point."""
        p = self.params
        self._speed_xy, self._speed_up, self._speed_down = (
            p.wpnav_speed,
            p.wpnav_speed_up,
            p.wpnav_speed_dn,
        )
        self._hold_ne = self.body.stopping_point(p.wpnav_accel)
        self._hold_alt = self._stopping_alt()
        self._guided_vel = None
        self._guided_yaw = None

    def guided_hold(self) -> None:
        """Re-initialise GUIDED to hold position (what ArduCopter does on a bad target)."""
        if self.mode is CopterMode.GUIDED:
            self._guided_hold()

    def enter_guided(self) -> MavResult:
        return self.set_mode(CopterMode.GUIDED)

    def takeoff(self, altitude: float) -> MavResult:
        """MAV_CMD_NAV_TAKEOFF: climb to ``altitude`` metres above home (Mode::do_user_takeoff)."""
        if not self.armed or not self.land_complete or self.mode not in _USER_TAKEOFF:
            return MavResult.FAILED
        if not math.isfinite(altitude):
            return MavResult.FAILED
        target = self._relative_to_origin(altitude)
        if target <= self.body.alt:
            return MavResult.FAILED
        self._takeoff_alt = target
        return MavResult.ACCEPTED

    def nav_takeoff(self, altitude: float, frame: int) -> MavResult:
        """MAV_CMD_NAV_TAKEOFF from a GCS: ArduCopter takes it in the current (guided)
        mode, with an altitude above home; PX4 switches to AUTO.TAKEOFF, with an altitude
        above mean sea level (NaN: MIS_TAKEOFF_ALT)."""
        if not self.personality.takeoff_alt_is_amsl:
            if frame not in _RELATIVE_TAKEOFF_FRAMES:
                return MavResult.DENIED
            return self.takeoff(altitude)
        above_home = altitude - self.home.alt if math.isfinite(altitude) else PX4_TAKEOFF_ALT_M
        return self._autopilot_takeoff(max(above_home, PX4_TAKEOFF_ALT_M))

    def _autopilot_takeoff(self, above_home: float) -> MavResult:
        """PX4's Takeoff mode: climb where it stands, then Hold."""
        if not (self.armed and self.land_complete and self.position_ok):
            return self.personality.declined
        self._enter_mode(CopterMode.GUIDED)
        self._takeoff_alt = self._relative_to_origin(above_home)
        self.personality.takeoff_selected()
        return MavResult.ACCEPTED

    def guided_goto(self, lat: float, lon: float, relative_alt: float) -> MavResult:
        """Fly to a position in GUIDED (ModeGuided::set_destination)."""
        if self.mode is not CopterMode.GUIDED:
            return MavResult.FAILED
        if not (-90.0 <= lat <= 90.0 and -180.0 <= lon <= 180.0) or not math.isfinite(relative_alt):
            return MavResult.DENIED
        self._hold_ne = self.ne_of(lat, lon)
        self._hold_alt = self._relative_to_origin(relative_alt)
        self._taking_off = False
        self._guided_vel = None  # a position-only target flies to it and stops
        self._guided_yaw = None
        return MavResult.ACCEPTED

    def guided_posvel(
        self,
        position: tuple[float, float, float] | None,
        velocity_ned: tuple[float, float, float],
        yaw: float | None = None,
    ) -> MavResult:
        """A GUIDED position-and-velocity target (ModeGuided::set_destination_posvelaccel),
        or a velocity-only one (``position`` None: ModeGuided::set_velaccel). The target
        then moves at that velocity between messages, as AC_PosControl integrates it, and
        the velocity is the position controller's feed-forward. ``position`` is (lat, lon,
        altitude above home); the velocity is north, east, down in m/s."""
        if self.mode is not CopterMode.GUIDED:
            return MavResult.FAILED
        if not all(math.isfinite(v) for v in velocity_ned):
            return MavResult.DENIED
        if position is None:
            if self._guided_vel is None:
                # from a position hold, the target starts where the vehicle is
                self._hold_ne = (self.body.north, self.body.east)
                self._hold_alt = self.body.alt
        elif self.guided_goto(*position) is not MavResult.ACCEPTED:
            return MavResult.DENIED
        vn, ve, vd = velocity_ned
        self._guided_yaw = yaw if yaw is not None and math.isfinite(yaw) else None
        self._guided_vel = (vn, ve, -vd)
        self._guided_vel_at = self.time_s
        self._taking_off = False
        return MavResult.ACCEPTED

    def _guided_setpoint(self) -> Setpoint:
        """GUIDED's demand this step: the target moves on at its velocity until
        GUID_TIMEOUT passes without a fresh one (ModeGuided::posvel_control_run then
        zeroes the velocity and the vehicle stops on the last target)."""
        velocity = (0.0, 0.0, 0.0)
        if self._guided_vel is not None:
            if self.time_s - self._guided_vel_at > self.params.guid_timeout:
                self._guided_vel = None
            else:
                velocity = self._guided_vel
                north, east = self._hold_ne
                self._hold_ne = (north + velocity[0] * DT, east + velocity[1] * DT)
                self._hold_alt = max(0.0, self._hold_alt + velocity[2] * DT)
        return Setpoint(
            self._hold_ne,
            self._hold_alt,
            speed_xy=self._speed_xy,
            speed_up=self._speed_up,
            speed_down=self._speed_down,
            velocity_ff=velocity,
            yaw_target=self._guided_yaw,
        )

    def set_guided_speed(self, kind: int, speed: float) -> MavResult:
        """MAV_CMD_DO_CHANGE_SPEED in GUIDED or AUTO: 0/1 horizontal, 2 climb, 3 descent, m/s."""
        if not (speed > 0.0 and math.isfinite(speed)) or self.mode not in (
            CopterMode.GUIDED,
            CopterMode.AUTO,
        ):
            return MavResult.FAILED
        if kind in (0, 1):
            self._speed_xy = speed
        elif kind == 2:
            self._speed_up = speed
        elif kind == 3:
            self._speed_down = speed
        else:
            return MavResult.FAILED
        return MavResult.ACCEPTED

    def change_speed(self, kind: int, speed: float) -> MavResult:
        return self.set_guided_speed(kind, speed)

    # -- parameters ------------------------------------------------------------

    def _params_changed(self, old: CopterParams, new: CopterParams) -> None:
        # AC_WPNav::update_wpnav: a changed WPNAV_SPEED* replaces the speed in use
        if new.wpnav_speed != old.wpnav_speed:
            self._speed_xy = new.wpnav_speed
        if new.wpnav_speed_up != old.wpnav_speed_up:
            self._speed_up = new.wpnav_speed_up
        if new.wpnav_speed_dn != old.wpnav_speed_dn:
            self._speed_down = new.wpnav_speed_dn

    def _takeoff_ready(self) -> bool:
        spooled = self.time_s - self._armed_at >= self.params.arming_delay + self.params.spool_time
        return self._takeoff_alt is not None and spooled

    def _start_takeoff(self) -> None:
        assert self._takeoff_alt is not None
        self.land_complete = False
        self._taking_off = True
        self._on_ground_s = 0.0
        self._hold_ne = (self.body.north, self.body.east)
        self._hold_alt = self._takeoff_alt
        self._takeoff_alt = None
