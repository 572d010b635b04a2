"""The simulated multirotor: its jobs combined, and the physics step that runs them."""

from __future__ import annotations

import math
from typing import Self

from common.geodesy import GeoPoint
from simulator.copter.arming import Arming
from simulator.copter.auto import Auto
from simulator.copter.failsafes import Failsafes
from simulator.copter.guided import Guided
from simulator.copter.landing import ReturnAndLand
from simulator.copter.modes import Modes
from simulator.copter.state import BRAKE_DECEL, BRAKE_SPEED_Z
from simulator.mavconst import CopterMode
from simulator.vehicle import DT, AutoPhase
from simulator.vehicle.battery import current_draw
from simulator.vehicle.physics import Setpoint, wrap_2pi

# ArduCopter's THR_DZ default, 100 of 1000 either side of mid stick.
THROTTLE_DEADZONE = 0.1
STICK_LEAD_S = 1.0


class Copter(Arming, Modes, Guided, Auto, ReturnAndLand, Failsafes):
    """One multirotor: state, the rules for changing it, and the physics that moves it."""

    def _reborn(self, origin: GeoPoint, boot_at: float) -> Self:
        return type(self)(
            origin,
            self.params,
            system_id=self.system_id,
            seed=self.seed,
            boot_at=boot_at,
            personality=type(self.personality)(),
        )

    # -- stepping ----------------------------------------------------------

    def _step(self) -> None:
        p = self.params
        setpoint = self._control()
        self.body.step(setpoint, DT, p)
        self._detect_landing(setpoint)
        self._check_auto_disarm()
        amps = current_draw(self.armed, self.flying, self.body.throttle, p.hover_throttle)
        self.battery.step(DT, amps, p.sim_batt_drain)
        self._check_battery()
        self._check_manual_loss()
        self._step_sensors()

    def _loiter_sticks(self, sticks: tuple[int, int, int, int]) -> Setpoint:
        """ModeLoiter with the sticks deflected: pitch and roll ask for a horizontal
        velocity in the vehicle's frame up to LOIT_SPEED, throttle away from mid (outside
        a 10 % dead zone) for a climb or descent up to PILOT_SPEED_UP/DN, yaw stick for a
        turn at up to ATC_SLEW_YAW; the loiter target moves with them."""
        p = self.params
        x, y, z, r = (value / 1000.0 for value in sticks)
        yaw = self.body.yaw
        forward, right = x * p.loit_speed, y * p.loit_speed
        vn = forward * math.cos(yaw) - right * math.sin(yaw)
        ve = forward * math.sin(yaw) + right * math.cos(yaw)
        # The target leads the vehicle by STICK_LEAD_S at the asked velocity, and the
        # speed limits are that velocity: the position controller then flies it.
        self._hold_ne = (self.body.north + vn * STICK_LEAD_S, self.body.east + ve * STICK_LEAD_S)
        climb = (z - 0.5) / 0.5  # -1 .. 1
        up, down = p.pilot_speed_up, p.pilot_speed_dn or p.pilot_speed_up
        if abs(climb) > THROTTLE_DEADZONE:
            rate = up if climb > 0 else down
            self._hold_alt = max(0.0, self.body.alt + climb * rate * STICK_LEAD_S)
        self.body.yaw = wrap_2pi(yaw + r * p.yaw_rate_max * DT)
        return Setpoint(
            self._hold_ne,
            self._hold_alt,
            speed_xy=max(p.loit_speed * math.hypot(x, y), 0.1),
            speed_up=up,
            speed_down=down,
            face_travel=False,
        )

    def _control(self) -> Setpoint | None:
        """This step's demand on the position controller; None for no thrust."""
        if not self.armed:
            return None
        if (
            self.mode is CopterMode.AUTO
            and self._auto_phase is AutoPhase.IDLE
            and self.mission_count > 0
        ):
            self._auto_begin()
        if self.land_complete:
            if self.mode in (CopterMode.LAND, CopterMode.BRAKE):
                # ModeLand::run and ModeBrake::run disarm as soon as they find it landed
                self._disarm()
                return None
            if not self._takeoff_ready():
                return None
            self._start_takeoff()
        if self._taking_off and self.body.alt >= self._hold_alt - 0.1:
            self._taking_off = False  # take-off complete: hold there
        if self.mode is CopterMode.STABILIZE:
            # sticks centred: level out and hold the altitude
            return Setpoint(None, self._hold_alt)
        if self.mode is CopterMode.LAND:
            return self._landing_setpoint(self._land_ne)
        if self.mode is CopterMode.RTL:
            return self._rtl_setpoint()
        if self.mode is CopterMode.BRAKE:
            return Setpoint(
                self._hold_ne,
                self._hold_alt,
                speed_xy=max(self.params.wpnav_speed, self.body.groundspeed),
                speed_up=BRAKE_SPEED_Z,
                speed_down=BRAKE_SPEED_Z,
                face_travel=False,
                accel_xy=BRAKE_DECEL,
            )
        if self.mode is CopterMode.AUTO and self._auto_phase is not AutoPhase.IDLE:
            return self._auto_setpoint()
        if self.mode is CopterMode.GUIDED:
            return self._guided_setpoint()
        # LOITER, and AUTO without a mission (only reachable by a forced arm): hold
        if self.mode is CopterMode.LOITER and self.personality.sticks_fly(self.mode):
            # A GCS's take-off climbs on; after it the transmitter's sticks rule (ArduPilot's
            # throttle at its minimum descends) unless a GCS overrides them.
            transmitter = None if self._taking_off else self.personality.transmitter_sticks()
            sticks = self.overridden_sticks() or transmitter
            if sticks is not None:
                return self._loiter_sticks(sticks)
        speed = self.params.wpnav_speed
        return Setpoint(self._hold_ne, self._hold_alt, speed_xy=speed, face_travel=False)
