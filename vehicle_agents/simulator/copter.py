"""The simulated vehicle: ArduCopter's arming rules, flight modes and navigation.

Pure logic, no I/O and no wall clock: time moves only through `advance`, in fixed
physics steps of `DT` sim seconds, so a run is the same whatever the speed-up and however
the elapsed time is sliced. Commands return a `MavResult`; anything ArduCopter would say
in a STATUSTEXT is queued and collected with `drain_texts`.

Behaviour follows ArduCopter 4.x (ArduCopter/mode*.cpp, AP_Arming_Copter.cpp):

* arming is refused without a 3D fix in modes that need a position, and in RTL, LAND and
  AUTO ("mode not armable"); param2=2989 forces it past everything but the position check;
* a GCS disarm is refused while flying unless forced (param2=21196);
* after arming the motors idle for ARMING_DELAY plus the spool-up time before a take-off;
* on the ground and armed for DISARM_DELAY it disarms itself; LAND and RTL disarm as soon
  as the land detector (1 s resting on the ground) reports touchdown;
* home moves to the vehicle's position when it arms, as on a vehicle whose home is not
  locked.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from enum import Enum

from vehicle_agents.simulator.battery import Battery, current_draw
from vehicle_agents.simulator.geo import GeoPoint, LocalFrame
from vehicle_agents.simulator.mavconst import (
    SUPPORTED_MODES,
    CopterMode,
    LandedState,
    MavResult,
    MavState,
    ModeFlag,
    Severity,
)
from vehicle_agents.simulator.params import CopterParams
from vehicle_agents.simulator.physics import Airframe, Setpoint, sqrt_controller

DT = 0.02  # physics step, sim seconds
_STEP_EPSILON = 1e-6  # in steps: absorbs float error when summing many small increments

# Modes that need a position estimate (Mode::requires_GPS) ...
_POSITION_MODES = frozenset({CopterMode.GUIDED, CopterMode.LOITER, CopterMode.RTL, CopterMode.AUTO})
# ... that refuse to arm (Mode::allows_arming is false) ...
_NOT_ARMABLE = frozenset({CopterMode.RTL, CopterMode.LAND, CopterMode.AUTO})
# ... that accept MAV_CMD_NAV_TAKEOFF on the ground (Mode::has_user_takeoff) ...
_USER_TAKEOFF = frozenset({CopterMode.GUIDED, CopterMode.LOITER})
# ... and that ArduCopter reports with MAV_MODE_FLAG_GUIDED_ENABLED.
_GUIDED_FLAG_MODES = frozenset(
    {CopterMode.AUTO, CopterMode.GUIDED, CopterMode.LOITER, CopterMode.RTL}
)


@dataclass(frozen=True)
class StatusText:
    severity: Severity
    text: str


class RtlStage(Enum):
    CLIMB = "climb"
    RETURN = "return"
    LOITER = "loiter"
    LAND = "land"


class Copter:
    """One multirotor: state, the rules for changing it, and the physics that moves it."""

    def __init__(self, home: GeoPoint, params: CopterParams | None = None) -> None:
        self.params = params or CopterParams()
        # The EKF origin: local north/east/down are measured from here, and the ground
        # is flat at its altitude.
        self.frame = LocalFrame(home)
        self.body = Airframe()
        self.battery = Battery()
        self.mode = CopterMode.STABILIZE  # ArduCopter's INITIAL_MODE
        self.armed = False
        self.land_complete = True
        self.gps_fix_type = 3
        self.satellites = 10
        self.mission_items = 0  # missions are not simulated yet
        self.home_ne = (0.0, 0.0)

        self._steps = 0
        self._target_time = 0.0
        self._texts: list[StatusText] = []

        p = self.params
        self._hold_ne = (0.0, 0.0)
        self._hold_alt = 0.0
        self._speed_xy = p.wpnav_speed
        self._speed_up = p.wpnav_speed_up
        self._speed_down = p.wpnav_speed_dn
        self._takeoff_alt: float | None = None  # accepted, waiting for the motors
        self._taking_off = False
        self._land_ne = (0.0, 0.0)
        self._rtl_stage = RtlStage.CLIMB
        self._rtl_origin_ne = (0.0, 0.0)
        self._rtl_alt = 0.0
        self._rtl_loiter_s = 0.0
        self._armed_at = 0.0
        self._on_ground_s = 0.0
        self._disarm_timer_s = 0.0

    # -- time --------------------------------------------------------------

    @property
    def time_s(self) -> float:
        """Sim seconds since boot (whole physics steps)."""
        return self._steps * DT

    def advance(self, dt: float) -> None:
        """Let ``dt`` sim seconds pass (any size; stepped internally at `DT`)."""
        if dt > 0.0:
            self._target_time += dt
            self._run_due_steps()

    def advance_to(self, sim_time: float) -> None:
        """Catch up with a clock reading ``sim_time`` sim seconds since boot."""
        if sim_time > self._target_time:
            self._target_time = sim_time
            self._run_due_steps()

    def _run_due_steps(self) -> None:
        due = math.floor(self._target_time / DT + _STEP_EPSILON)
        while self._steps < due:
            self._step()

    # -- derived state -----------------------------------------------------

    @property
    def position_ok(self) -> bool:
        return self.gps_fix_type >= 3

    @property
    def flying(self) -> bool:
        return self.armed and not self.land_complete

    @property
    def home(self) -> GeoPoint:
        return self.frame.to_global(self.home_ne[0], self.home_ne[1], 0.0)

    def position(self) -> GeoPoint:
        return self.frame.to_global(self.body.north, self.body.east, self.body.alt)

    @property
    def altitude_msl(self) -> float:
        return self.frame.home.alt + self.body.alt

    @property
    def relative_alt(self) -> float:
        """Metres above home (home is on the same flat ground as the origin)."""
        return self.body.alt

    def base_mode(self) -> int:
        """HEARTBEAT.base_mode as GCS_MAVLINK_Copter::base_mode() builds it."""
        flags = (
            ModeFlag.CUSTOM_MODE_ENABLED
            | ModeFlag.STABILIZE_ENABLED
            | ModeFlag.MANUAL_INPUT_ENABLED
        )
        if self.mode in _GUIDED_FLAG_MODES:
            flags |= ModeFlag.GUIDED_ENABLED
        if self.armed:
            flags |= ModeFlag.SAFETY_ARMED
        return int(flags)

    def system_status(self) -> MavState:
        """STANDBY while landed (armed or not), ACTIVE in the air, as ArduCopter reports."""
        return MavState.STANDBY if self.land_complete else MavState.ACTIVE

    def landed_state(self) -> LandedState:
        if self.land_complete:
            return LandedState.ON_GROUND
        if self.mode is CopterMode.LAND or (
            self.mode is CopterMode.RTL and self._rtl_stage is RtlStage.LAND
        ):
            return LandedState.LANDING
        if self._taking_off:
            return LandedState.TAKEOFF
        return LandedState.IN_AIR

    def prearm_ok(self) -> bool:
        """Whether the pre-arm checks pass in the current mode (SYS_STATUS PREARM bit)."""
        return self.position_ok or self.mode not in _POSITION_MODES

    @property
    def guided_target(self) -> tuple[float, float, float] | None:
        """(north, east, alt) the vehicle is holding or flying to in GUIDED, if any."""
        if self.mode is not CopterMode.GUIDED:
            return None
        return self._hold_ne[0], self._hold_ne[1], self._hold_alt

    def drain_texts(self) -> list[StatusText]:
        texts, self._texts = self._texts, []
        return texts

    def _say(self, severity: Severity, text: str) -> None:
        self._texts.append(StatusText(severity, text))

    # -- commands ----------------------------------------------------------

    def arm(self, force: bool = False) -> MavResult:
        """MAV_CMD_COMPONENT_ARM_DISARM param1=1; ``force`` is param2=2989."""
        if self.armed:
            return MavResult.ACCEPTED
        needs_position = self.mode in _POSITION_MODES
        if force:
            # only the mandatory checks run
            if needs_position and not self.position_ok:
                self._say(Severity.CRITICAL, "Arm: Need Position Estimate")
                return MavResult.FAILED
        else:
            if needs_position and not self.position_ok:
                self._say(Severity.CRITICAL, "Arm: GPS 1: Bad fix")
                return MavResult.FAILED
            if self.mode in _NOT_ARMABLE:
                self._say(Severity.CRITICAL, f"Arm: {self.mode.name} mode not armable")
                return MavResult.FAILED
        self.armed = True
        self._armed_at = self.time_s
        self._disarm_timer_s = 0.0
        self._takeoff_alt = None
        if self.body.on_ground:
            self.land_complete = True
            self.home_ne = (self.body.north, self.body.east)
        self._say(Severity.INFO, "Arming motors")
        return MavResult.ACCEPTED

    def disarm(self, force: bool = False) -> MavResult:
        """MAV_CMD_COMPONENT_ARM_DISARM param1=0; ``force`` is param2=21196."""
        if not self.armed:
            return MavResult.ACCEPTED
        if not force and not self.land_complete:
            return MavResult.FAILED
        self._disarm()
        return MavResult.ACCEPTED

    def _disarm(self) -> None:
        self.armed = False
        self.land_complete = True
        self._takeoff_alt = None
        self._taking_off = False
        self._say(Severity.INFO, "Disarming motors")

    def set_mode(self, number: int) -> MavResult:
        """Copter::set_mode for a GCS request."""
        if number == self.mode:
            return MavResult.ACCEPTED
        try:
            mode = CopterMode(number)
        except ValueError:
            self._say(Severity.WARNING, f"No such mode {number}")
            return MavResult.FAILED
        if mode not in SUPPORTED_MODES:
            self._say(Severity.WARNING, f"Mode change to {mode.name} failed: not simulated")
            return MavResult.FAILED
        ignore_checks = not self.armed  # any mode may be selected while disarmed
        if not ignore_checks and mode in _POSITION_MODES and not self.position_ok:
            self._say(Severity.WARNING, f"Mode change to {mode.name} failed: requires position")
            return MavResult.FAILED
        if mode is CopterMode.AUTO and not ignore_checks and self.mission_items == 0:
            # ModeAuto::init: no mission present
            self._say(Severity.WARNING, "Mode change to AUTO failed: init failed")
            return MavResult.FAILED
        self._enter_mode(mode)
        return MavResult.ACCEPTED

    def _enter_mode(self, mode: CopterMode) -> None:
        p = self.params
        # leaving a mode cancels any take-off in progress
        self._takeoff_alt = None
        self._taking_off = False
        self.mode = mode
        stop_ne = self.body.stopping_point(p.wpnav_accel)
        if mode in (CopterMode.STABILIZE, CopterMode.LOITER, CopterMode.AUTO):
            self._hold_ne = stop_ne
            self._hold_alt = self._stopping_alt()
        elif mode is CopterMode.GUIDED:
            self._guided_hold()
        elif mode is CopterMode.LAND:
            self._land_ne = stop_ne
        elif mode is CopterMode.RTL:
            self._start_rtl(stop_ne)

    def _stopping_alt(self) -> float:
        climb = self.body.climb_rate
        return self.body.alt + climb * abs(climb) / (2.0 * self.params.wpnav_accel_z)

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

    def guided_hold(self) -> None:
        """Re-initialise GUIDED to hold position (what ArduCopter does on a bad target)."""
        if self.mode is CopterMode.GUIDED:
            self._guided_hold()

    def takeoff(self, altitude: float) -> MavResult:
        """MAV_CMD_NAV_TAKEOFF: climb to ``altitude`` metres above home (Mode::do_user_takeoff)."""
        if not self.armed or not self.land_complete or self.mode not in _USER_TAKEOFF:
            return MavResult.FAILED
        if not math.isfinite(altitude) or altitude <= self.body.alt:
            return MavResult.FAILED
        self._takeoff_alt = altitude
        return MavResult.ACCEPTED

    def guided_goto(self, lat: float, lon: float, relative_alt: float) -> MavResult:
        """Fly to a position in GUIDED (ModeGuided::set_destination)."""
        if self.mode is not CopterMode.GUIDED:
            return MavResult.FAILED
        if not (-90.0 <= lat <= 90.0 and -180.0 <= lon <= 180.0) or not math.isfinite(relative_alt):
            return MavResult.DENIED
        self._hold_ne = self.frame.to_local(lat, lon)
        self._hold_alt = relative_alt
        self._taking_off = False
        return MavResult.ACCEPTED

    def set_guided_speed(self, kind: int, speed: float) -> MavResult:
        """MAV_CMD_DO_CHANGE_SPEED: 0/1 horizontal, 2 climb, 3 descent, in m/s."""
        if not (speed > 0.0 and math.isfinite(speed)) or self.mode is not CopterMode.GUIDED:
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

    # -- fault injection (tests, demo) -----------------------------------------

    def set_gps_fix(self, fix_type: int, satellites: int | None = None) -> None:
        self.gps_fix_type = fix_type
        self.satellites = satellites if satellites is not None else (10 if fix_type >= 3 else 0)

    # -- stepping ----------------------------------------------------------

    def _step(self) -> None:
        setpoint = self._control()
        self.body.step(setpoint, DT, self.params)
        self._detect_landing(setpoint)
        self._check_auto_disarm()
        amps = current_draw(self.armed, self.flying, self.body.throttle, self.params.hover_throttle)
        self.battery.step(DT, amps)
        self._steps += 1

    def _control(self) -> Setpoint | None:
        """This step's demand on the position controller; None for no thrust."""
        if not self.armed:
            return None
        if self.land_complete:
            if self.mode is CopterMode.LAND:
                # ModeLand::run disarms as soon as it finds itself landed
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
        if self.mode is CopterMode.GUIDED:
            return Setpoint(
                self._hold_ne,
                self._hold_alt,
                speed_xy=self._speed_xy,
                speed_up=self._speed_up,
                speed_down=self._speed_down,
            )
        # LOITER, and AUTO (only reachable by a forced arm): hold position
        speed = self.params.wpnav_speed
        return Setpoint(self._hold_ne, self._hold_alt, speed_xy=speed, face_travel=False)

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
        """ModeRTL::build_path and compute_return_target."""
        p = self.params
        current = self.body.alt
        distance = math.dist(stop_ne, self.home_ne)
        target = max(0.0, current + max(0.0, p.rtl_climb_min))
        target = max(target, max(p.rtl_alt, p.rtl_alt_min))
        if p.rtl_cone_slope >= 0.5:
            target = max(
                current,
                min(target, max(distance * p.rtl_cone_slope, current + p.rtl_abs_min_climb)),
            )
        self._rtl_origin_ne = stop_ne
        self._rtl_alt = target
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

    # -- land detector and auto-disarm ---------------------------------------

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
        if self.mode is CopterMode.LAND or self.mode is CopterMode.RTL:
            self._disarm()

    def _check_auto_disarm(self) -> None:
        """Copter::auto_disarm_check: landed and armed for DISARM_DELAY."""
        if not (self.armed and self.land_complete) or self.params.disarm_delay <= 0.0:
            self._disarm_timer_s = 0.0
            return
        self._disarm_timer_s += DT
        if self._disarm_timer_s + 1e-9 >= self.params.disarm_delay:
            self._disarm()
