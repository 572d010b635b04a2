"""A kinematic point-mass multirotor with ArduPilot-style position control.

Wind (SIM_WIND_SPD/SIM_WIND_DIR) is felt as drag on the velocity through the air: the
position controller holds its track against it (as ArduPilot's integrators do), so wind
shows as lean into it, as airspeed, and as drift when there is no thrust.

The position controller turns a `Setpoint` into desired velocities with ArduPilot's
square-root controller (so the vehicle decelerates in time to stop on its target), and
the velocity follows at bounded acceleration. Attitude is derived: roll and pitch from
the acceleration (plus a little drag), heading turning toward the direction of travel at
a bounded yaw rate. Stepping is a fixed ``dt``; `Copter` decides how many steps to run.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from simulator.params.values import CopterParams

GRAVITY = 9.80665
DRAG_PER_S = 0.15  # linear drag: the tilt needed to hold a speed (about 4 deg at 5 m/s)
ATTITUDE_TIME_CONSTANT_S = 0.2
FACE_TRAVEL_MIN_SPEED = 1.0  # below this ground speed the heading is held
MAX_FALL_SPEED = 40.0
GROUND_TOLERANCE_M = 1e-3


def sqrt_controller(error: float, p: float, accel_max: float, dt: float) -> float:
    """ArduPilot's ``sqrt_controller``: linear near zero, constant deceleration further out.

    Returns the velocity that brings ``error`` to zero without exceeding ``accel_max``.
    """
    if accel_max <= 0.0:
        correction = error * p
    elif p <= 0.0:
        correction = math.copysign(math.sqrt(2.0 * accel_max * abs(error)), error)
    else:
        linear_dist = accel_max / (p * p)
        if abs(error) > linear_dist:
            correction = math.copysign(
                math.sqrt(2.0 * accel_max * (abs(error) - linear_dist / 2.0)), error
            )
        else:
            correction = error * p
    if dt > 0.0:
        # never ask for more than closes the error in one step
        limit = abs(error) / dt
        correction = max(-limit, min(limit, correction))
    return correction


def wrap_pi(angle: float) -> float:
    return (angle + math.pi) % (2.0 * math.pi) - math.pi


def wrap_2pi(angle: float) -> float:
    return angle % (2.0 * math.pi)


def _clamp(value: float, low: float, high: float) -> float:
    return max(low, min(high, value))


def wind_ne(params: CopterParams) -> tuple[float, float]:
    """The wind's velocity (m/s north, east); SIM_WIND_DIR is where it blows from."""
    if params.sim_wind_spd <= 0.0:
        return 0.0, 0.0
    toward = math.radians(params.sim_wind_dir) + math.pi
    return params.sim_wind_spd * math.cos(toward), params.sim_wind_spd * math.sin(toward)


@dataclass(frozen=True)
class Setpoint:
    """One step's demand on the position controller.

    ``target_ne`` is a horizontal position to fly to (None: brake to a stop and drift no
    further). ``target_alt`` is an altitude above the ground at the origin (None: follow
    ``climb_rate``). ``accel_xy`` overrides WPNAV_ACCEL (BRAKE stops harder than a
    waypoint leg). ``on_wheels``: a ground vehicle, which drives along the ground instead of
    resting on skids, and turns to face its travel however slowly it moves.
    """

    target_ne: tuple[float, float] | None
    target_alt: float | None
    climb_rate: float = 0.0
    speed_xy: float = 5.0
    speed_up: float = 2.5
    speed_down: float = 1.5
    face_travel: bool = True
    accel_xy: float | None = None
    on_wheels: bool = False
    # A velocity feed-forward (north, east, up m/s) added to the position correction, as
    # AC_PosControl::input_pos_vel_accel_xy adds GUIDED's velocity target: the vehicle
    # then flies with a moving target instead of chasing it with a lag.
    velocity_ff: tuple[float, float, float] = (0.0, 0.0, 0.0)
    # A heading to turn to at the yaw rate limit (a GUIDED target's yaw); None: as
    # ``face_travel`` says.
    yaw_target: float | None = None


@dataclass
class Airframe:
    """Kinematic state, local NED metres from home (``down`` is negative when airborne)."""

    north: float = 0.0
    east: float = 0.0
    down: float = 0.0
    vn: float = 0.0
    ve: float = 0.0
    vd: float = 0.0
    yaw: float = 0.0  # radians, 0..2pi, clockwise from north
    roll: float = 0.0
    pitch: float = 0.0
    roll_rate: float = 0.0
    pitch_rate: float = 0.0
    yaw_rate: float = 0.0
    throttle: float = 0.0  # 0..1, share of full thrust

    @property
    def alt(self) -> float:
        """Metres above home."""
        return -self.down

    @property
    def on_ground(self) -> bool:
        return self.alt <= GROUND_TOLERANCE_M

    @property
    def groundspeed(self) -> float:
        return math.hypot(self.vn, self.ve)

    @property
    def climb_rate(self) -> float:
        return -self.vd

    def airspeed_ne(self, params: CopterParams) -> tuple[float, float]:
        """Velocity through the air (ground velocity less the wind's)."""
        wind_n, wind_e = wind_ne(params)
        return self.vn - wind_n, self.ve - wind_e

    def stopping_point(self, accel: float) -> tuple[float, float]:
        """Where the vehicle comes to rest braking at ``accel`` from its current velocity."""
        speed = self.groundspeed
        if speed < 1e-6 or accel <= 0.0:
            return self.north, self.east
        distance = speed * speed / (2.0 * accel)
        return self.north + self.vn / speed * distance, self.east + self.ve / speed * distance

    # -- stepping ----------------------------------------------------------

    def step(self, setpoint: Setpoint | None, dt: float, params: CopterParams) -> None:
        """Advance ``dt`` seconds. ``None`` means no thrust (disarmed or idling on the ground)."""
        if setpoint is None:
            self._step_unpowered(dt, params)
        else:
            self._step_powered(setpoint, dt, params)

    def _step_unpowered(self, dt: float, params: CopterParams) -> None:
        old_roll, old_pitch = self.roll, self.pitch
        self.throttle = 0.0
        if self.on_ground and self.vd >= 0.0:
            self.vn = self.ve = self.vd = 0.0
            self.down = 0.0
        else:
            # falling, the air carries it along: velocity relaxes toward the wind's
            wind_n, wind_e = wind_ne(params)
            decay = max(0.0, 1.0 - DRAG_PER_S * dt)
            self.vn = wind_n + (self.vn - wind_n) * decay
            self.ve = wind_e + (self.ve - wind_e) * decay
            self.vd = min(self.vd + GRAVITY * dt, MAX_FALL_SPEED)
            self._integrate_position(dt)
        self.roll = 0.0 if self.on_ground else self.roll
        self.pitch = 0.0 if self.on_ground else self.pitch
        self.roll_rate = (self.roll - old_roll) / dt
        self.pitch_rate = (self.pitch - old_pitch) / dt
        self.yaw_rate = 0.0

    def _step_powered(self, sp: Setpoint, dt: float, params: CopterParams) -> None:
        # Horizontal: desired velocity toward the target, reached at bounded acceleration.
        accel = sp.accel_xy if sp.accel_xy is not None else params.wpnav_accel
        ff_n, ff_e, ff_up = sp.velocity_ff
        want_n = want_e = 0.0
        if sp.target_ne is not None:
            want_n, want_e = ff_n, ff_e
            err_n, err_e = sp.target_ne[0] - self.north, sp.target_ne[1] - self.east
            distance = math.hypot(err_n, err_e)
            if distance > 1e-9:
                speed = min(
                    sp.speed_xy,
                    sqrt_controller(distance, params.psc_posxy_p, accel, dt),
                )
                want_n += err_n / distance * speed
                want_e += err_e / distance * speed
            # the sum, feed-forward and correction, is held to the speed limit
            total = math.hypot(want_n, want_e)
            if total > sp.speed_xy:
                want_n, want_e = want_n / total * sp.speed_xy, want_e / total * sp.speed_xy
        dvn, dve = want_n - self.vn, want_e - self.ve
        dv = math.hypot(dvn, dve)
        max_dv = accel * dt
        if dv > max_dv:
            dvn, dve = dvn / dv * max_dv, dve / dv * max_dv

        # Vertical: to the target altitude, or at the demanded climb rate.
        if sp.target_alt is not None:
            want_up = ff_up + sqrt_controller(
                sp.target_alt - self.alt, params.psc_posz_p, params.wpnav_accel_z, dt
            )
        else:
            want_up = sp.climb_rate
        want_up = _clamp(want_up, -sp.speed_down, sp.speed_up)
        dvu = _clamp(
            want_up - self.climb_rate, -params.wpnav_accel_z * dt, params.wpnav_accel_z * dt
        )

        self.vn += dvn
        self.ve += dve
        self.vd -= dvu
        self._integrate_position(dt)
        if self.on_ground and want_up <= 0.0 and not sp.on_wheels:
            # resting on the ground: skids do not slide
            self.vn = self.ve = 0.0
            dvn = dve = 0.0

        self._update_attitude(dvn / dt, dve / dt, dvu / dt, sp, dt, params)
        if sp.on_wheels:
            # a ground vehicle's throttle follows its speed, not a hover
            self.throttle = _clamp(self.groundspeed / max(sp.speed_xy, 0.1), 0.0, 1.0)

    def _integrate_position(self, dt: float) -> None:
        self.north += self.vn * dt
        self.east += self.ve * dt
        self.down += self.vd * dt
        if self.down >= 0.0:
            self.down = 0.0
            self.vd = min(self.vd, 0.0)

    def _update_attitude(
        self,
        accel_n: float,
        accel_e: float,
        accel_up: float,
        sp: Setpoint,
        dt: float,
        params: CopterParams,
    ) -> None:
        old_roll, old_pitch = self.roll, self.pitch
        # Heading: toward the direction of travel, at a bounded yaw rate.
        self.yaw_rate = 0.0
        # a multirotor on its skids does not turn; a ground vehicle steers at any speed
        turning_speed = 0.05 if sp.on_wheels else FACE_TRAVEL_MIN_SPEED
        can_turn = sp.on_wheels or not self.on_ground
        if sp.yaw_target is not None and can_turn:
            error = wrap_pi(sp.yaw_target - self.yaw)
            turn = _clamp(error, -params.yaw_rate_max * dt, params.yaw_rate_max * dt)
            self.yaw = wrap_2pi(self.yaw + turn)
            self.yaw_rate = turn / dt
        elif sp.face_travel and self.groundspeed > turning_speed and can_turn:
            error = wrap_pi(math.atan2(self.ve, self.vn) - self.yaw)
            turn = _clamp(error, -params.yaw_rate_max * dt, params.yaw_rate_max * dt)
            self.yaw = wrap_2pi(self.yaw + turn)
            self.yaw_rate = turn / dt

        if self.on_ground:
            target_roll = target_pitch = 0.0
        else:
            # Lean into the acceleration plus the drag being overcome (drag acts on the
            # velocity through the air, so a hover in wind leans into it), in the body frame.
            air_n, air_e = self.airspeed_ne(params)
            total_n = accel_n + DRAG_PER_S * air_n
            total_e = accel_e + DRAG_PER_S * air_e
            cos_yaw, sin_yaw = math.cos(self.yaw), math.sin(self.yaw)
            forward = total_n * cos_yaw + total_e * sin_yaw
            right = -total_n * sin_yaw + total_e * cos_yaw
            limit = params.angle_max
            target_pitch = _clamp(-math.atan2(forward, GRAVITY), -limit, limit)
            target_roll = _clamp(math.atan2(right, GRAVITY), -limit, limit)
        blend = dt / (ATTITUDE_TIME_CONSTANT_S + dt)
        self.roll += (target_roll - self.roll) * blend
        self.pitch += (target_pitch - self.pitch) * blend
        self.roll_rate = (self.roll - old_roll) / dt
        self.pitch_rate = (self.pitch - old_pitch) / dt

        if self.on_ground and accel_up <= 0.0:
            self.throttle = 0.0
        else:
            tilt = max(math.cos(self.roll) * math.cos(self.pitch), 0.5)
            thrust = params.hover_throttle * (GRAVITY + accel_up) / GRAVITY / tilt
            self.throttle = _clamp(thrust, 0.0, 1.0)
