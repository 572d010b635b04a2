"""The simulated multirotor: ArduCopter's arming rules, flight modes and navigation.

Pure logic, no I/O and no wall clock: time moves only through `advance`, in fixed
physics steps of `DT` sim seconds, so a run is the same whatever the speed-up and however
the elapsed time is sliced. Commands return a `MavResult`; anything ArduCopter would say
in a STATUSTEXT is queued and collected with `drain_texts`. A `Personality` decides which
autopilot it shows itself as on the wire (ArduCopter, or PX4's mode encoding).

Behaviour follows ArduCopter 4.x (ArduCopter/mode*.cpp, AP_Arming_Copter.cpp):

* arming is refused without a 3D fix in modes that need a position, and in RTL, LAND,
  AUTO and BRAKE ("mode not armable"); param2=2989 forces it past everything but the
  position check;
* a GCS disarm is refused while flying unless forced (param2=21196);
* after arming the motors idle for ARMING_DELAY plus the spool-up time before a take-off;
* on the ground and armed for DISARM_DELAY it disarms itself; LAND and RTL disarm as soon
  as the land detector (1 s resting on the ground) reports touchdown, BRAKE at once;
* BRAKE stops as hard as BRAKE_MODE_DECEL_RATE allows and holds there;
* home moves to the vehicle's position when it arms, unless a GCS has set (and so
  locked) it with MAV_CMD_DO_SET_HOME.
"""

from __future__ import annotations

import math
from enum import Enum
from typing import Self

from common.geodesy import GeoPoint
from simulator.battery import current_draw
from simulator.mavconst import (
    SUPPORTED_MODES,
    CopterMode,
    LandedState,
    MavCmd,
    MavFrame,
    MavResult,
    MavState,
    MavType,
    Severity,
)
from simulator.mission import MissionItem
from simulator.param_table import ParamTable
from simulator.params import CopterParams
from simulator.personality import (
    PX4_TAKEOFF_ALT_M,
    ArduCopterPersonality,
    Declined,
    ModeRequest,
    Personality,
)
from simulator.physics import Setpoint, sqrt_controller
from simulator.vehicle import (
    DT,
    AutoPhase,
    Event,
    ItemReached,
    PhotoTaken,
    StatusText,
    Vehicle,
)

__all__ = [
    "DT",
    "AutoPhase",
    "Copter",
    "Event",
    "ItemReached",
    "PhotoTaken",
    "RtlStage",
    "StatusText",
]

TAKEOFF_DONE_M = 0.1  # a take-off is complete this close to its altitude
WAYPOINT_ALT_TOLERANCE_M = 1.0
BRAKE_DECEL = 7.5  # BRAKE_MODE_DECEL_RATE, m/s/s
BRAKE_SPEED_Z = 2.5  # BRAKE_MODE_SPEED_Z, m/s

# Modes that need a position estimate (Mode::requires_GPS) ...
_POSITION_MODES = frozenset(
    {CopterMode.GUIDED, CopterMode.LOITER, CopterMode.RTL, CopterMode.AUTO, CopterMode.BRAKE}
)
# ... and that accept MAV_CMD_NAV_TAKEOFF on the ground (Mode::has_user_takeoff).
_USER_TAKEOFF = frozenset({CopterMode.GUIDED, CopterMode.LOITER})
_RELATIVE_TAKEOFF_FRAMES = frozenset(
    {MavFrame.GLOBAL_RELATIVE_ALT, MavFrame.GLOBAL_RELATIVE_ALT_INT}
)


class RtlStage(Enum):
    CLIMB = "climb"
    RETURN = "return"
    LOITER = "loiter"
    LAND = "land"


class Copter(Vehicle):
    """One multirotor: state, the rules for changing it, and the physics that moves it."""

    mode: CopterMode

    def __init__(
        self,
        home: GeoPoint,
        params: CopterParams | None = None,
        *,
        system_id: int = 1,
        seed: int = 0,
        boot_at: float = 0.0,
        personality: Personality | None = None,
    ) -> None:
        # first: it decides the parameter table the base class builds
        self.personality = personality or ArduCopterPersonality()
        super().__init__(home, params, system_id=system_id, seed=seed, boot_at=boot_at)
        self.mode = CopterMode.STABILIZE  # ArduCopter's INITIAL_MODE
        self.land_complete = True

        p = self.params
        self._hold_ne = (0.0, 0.0)
        self._hold_alt = 0.0  # metres above the ground at the origin
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

    def _reborn(self, origin: GeoPoint, boot_at: float) -> Self:
        return type(self)(
            origin,
            self.params,
            system_id=self.system_id,
            seed=self.seed,
            boot_at=boot_at,
            personality=type(self.personality)(),
        )

    # -- what the vehicle is -----------------------------------------------

    @property
    def mav_type(self) -> int:
        return int(MavType.QUADROTOR)

    @property
    def autopilot(self) -> int:
        return int(self.personality.autopilot)

    def base_mode(self) -> int:
        """HEARTBEAT.base_mode as the autopilot builds it."""
        return self.personality.base_mode(self.mode, self.armed)

    def custom_mode(self) -> int:
        return self.personality.custom_mode(self.mode, self.taking_off)

    @property
    def manual_mode(self) -> bool:
        return self.mode is CopterMode.STABILIZE

    @property
    def flying(self) -> bool:
        return self.armed and not self.land_complete

    @property
    def taking_off(self) -> bool:
        """A take-off accepted and not yet at its altitude."""
        return self._takeoff_alt is not None or self._taking_off

    @property
    def _camera_moving(self) -> bool:
        return self.flying

    def system_status(self) -> MavState:
        return self.personality.system_status(self.armed, self.land_complete, self.battery_failsafe)

    def landed_state(self) -> LandedState:
        if self.land_complete:
            return LandedState.ON_GROUND
        if self._landing():
            return LandedState.LANDING
        if self._taking_off:
            return LandedState.TAKEOFF
        return LandedState.IN_AIR

    def prearm_ok(self) -> bool:
        return self.position_ok or self.mode not in _POSITION_MODES

    @property
    def guided_target(self) -> tuple[float, float, float] | None:
        """(north, east, alt) the vehicle is holding or flying to in GUIDED, if any."""
        if self.mode is not CopterMode.GUIDED:
            return None
        return self._hold_ne[0], self._hold_ne[1], self._hold_alt

    @property
    def in_guided(self) -> bool:
        return self.mode is CopterMode.GUIDED

    @property
    def in_auto(self) -> bool:
        return self.mode is CopterMode.AUTO

    def _landing(self) -> bool:
        """In the descent of LAND, of RTL, or of a mission's NAV_LAND / RTL."""
        rtl_landing = self._rtl_stage is RtlStage.LAND
        if self.mode is CopterMode.AUTO:
            return self._auto_phase is AutoPhase.LAND or (
                self._auto_phase is AutoPhase.RTL and rtl_landing
            )
        return self.mode is CopterMode.LAND or (self.mode is CopterMode.RTL and rtl_landing)

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
        self._say(Severity.INFO, "Disarming motors")

    @property
    def reboot_declined(self) -> MavResult:
        return self.personality.reboot_declined

    @property
    def mission_wire_offset(self) -> int:
        return self.personality.mission_wire_offset

    def position_frame_ok(self, frame: int) -> bool:
        return self.personality.position_frame_ok(frame)

    @property
    def param_bytewise(self) -> bool:
        return self.personality.param_bytewise

    def _new_param_table(self, params: CopterParams, system_id: int) -> ParamTable:
        return self.personality.new_param_table(params, system_id)

    def set_mode(self, number: int) -> MavResult:
        """Copter::set_mode for a GCS request."""
        if number == self.mode:
            return MavResult.ACCEPTED
        mode = self._requested_mode(number, CopterMode, SUPPORTED_MODES)
        if mode is None:
            return MavResult.FAILED
        ignore_checks = not self.armed  # any mode may be selected while disarmed
        if not ignore_checks and mode in _POSITION_MODES and not self.position_ok:
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
        result = self.set_mode(request.mode)
        if result is not MavResult.ACCEPTED:
            return self.personality.declined
        self.personality.selected(request)
        return result

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

    def _stopping_alt(self, accel: float | None = None) -> float:
        climb = self.body.climb_rate
        decel = accel if accel is not None else self.params.wpnav_accel_z
        return self.body.alt + climb * abs(climb) / (2.0 * decel)

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
        return MavResult.ACCEPTED

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

    # -- missions --------------------------------------------------------------

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
        self._step_sensors()

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
            return Setpoint(
                self._hold_ne,
                self._hold_alt,
                speed_xy=self._speed_xy,
                speed_up=self._speed_up,
                speed_down=self._speed_down,
            )
        # LOITER, and AUTO without a mission (only reachable by a forced arm): hold
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
