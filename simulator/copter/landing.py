"""Coming down: LAND's descent and RTL's climb, return, loiter and landing (ModeLand, ModeRTL)."""

from __future__ import annotations

import math

from simulator.copter.state import CopterState, RtlStage
from simulator.vehicle import DT
from simulator.vehicle.physics import Setpoint, sqrt_controller


class ReturnAndLand(CopterState):
    """The landing descent and the return to launch."""

    def _landing_descent_rate(self) -> float:
        """Mode::land_run_vertical_control: fast down to LAND_ALT_LOW, then LAND_SPEED."""
        p = self.params
        fast = p.land_speed_high if p.land_speed_high > 0.0 else p.wpnav_speed_dn
        fast = max(fast, abs(p.land_speed))
        rate = sqrt_controller(
            max(p.land_alt_low, 1.0) - self.body.alt, p.psc_posz_p, p.wpnav_accel_z, DT
        )
        return max(-fast, min(-abs(p.land_speed), rate))

    def _landing_setpoint(self, target_ne: tuple[float, float]) -> Setpoint:
        p = self.params
        descent = self._landing_descent_rate()
        return Setpoint(
            target_ne,
            None,
            climb_rate=descent,
            speed_xy=p.wpnav_speed,
            speed_down=max(abs(descent), p.land_speed),
            face_travel=False,
        )

    # -- RTL -----------------------------------------------------------------

    def _start_rtl(self, stop_ne: tuple[float, float]) -> None:
        """ModeRTL::build_path and compute_return_target (altitudes above home)."""
        p = self.params
        current = self.relative_alt
        distance = math.dist(stop_ne, self.home_ne)
        target = max(0.0, current + max(0.0, p.rtl_climb_min))
        target = max(target, max(p.rtl_alt, p.rtl_alt_min))
        if p.rtl_cone_slope >= 0.5:
            target = max(
                current,
                min(target, max(distance * p.rtl_cone_slope, current + p.rtl_abs_min_climb)),
            )
        self._rtl_origin_ne = stop_ne
        self._rtl_alt = self._relative_to_origin(target)
        self._rtl_stage = RtlStage.CLIMB
        self._rtl_loiter_s = 0.0

    def _rtl_setpoint(self) -> Setpoint:
        p = self.params
        face_travel = p.wp_yaw_behavior != 2  # 2: face next waypoint except during RTL
        if self._rtl_stage is RtlStage.CLIMB:
            if abs(self.body.alt - self._rtl_alt) < 0.5:
                self._rtl_stage = RtlStage.RETURN
            else:
                return Setpoint(self._rtl_origin_ne, self._rtl_alt, face_travel=face_travel)
        if self._rtl_stage is RtlStage.RETURN:
            distance = math.hypot(
                self.home_ne[0] - self.body.north, self.home_ne[1] - self.body.east
            )
            if distance <= p.wpnav_radius:
                self._rtl_stage = RtlStage.LOITER
            else:
                return Setpoint(
                    self.home_ne, self._rtl_alt, speed_xy=p.wpnav_speed, face_travel=face_travel
                )
        if self._rtl_stage is RtlStage.LOITER:
            self._rtl_loiter_s += DT
            if self._rtl_loiter_s < p.rtl_loit_time:
                return Setpoint(self.home_ne, self._rtl_alt, face_travel=False)
            self._rtl_stage = RtlStage.LAND
        return self._landing_setpoint(self.home_ne)
