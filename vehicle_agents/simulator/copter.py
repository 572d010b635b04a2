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
import random
from dataclasses import dataclass
from enum import Enum

from vehicle_agents.simulator.battery import Battery, current_draw
from vehicle_agents.simulator.geo import GeoPoint, LocalFrame
from vehicle_agents.simulator.mavconst import (
    SUPPORTED_MODES,
    CopterMode,
    LandedState,
    MavCmd,
    MavFrame,
    MavResult,
    MavState,
    MissionState,
    ModeFlag,
    Severity,
)
from vehicle_agents.simulator.mission import ABSOLUTE_FRAMES, MissionItem
from vehicle_agents.simulator.param_table import ParamTable, SetOutcome
from vehicle_agents.simulator.params import CopterParams
from vehicle_agents.simulator.physics import Airframe, Setpoint, sqrt_controller

DT = 0.02  # physics step, sim seconds
GPS_PERIOD_STEPS = 10  # a GPS fix every 0.2 s (5 Hz), each with fresh noise
TAKEOFF_DONE_M = 0.1  # a take-off is complete this close to its altitude
WAYPOINT_ALT_TOLERANCE_M = 1.0
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


@dataclass(frozen=True)
class ItemReached:
    """MISSION_ITEM_REACHED: mission command ``seq`` is complete."""

    seq: int


@dataclass(frozen=True)
class PhotoTaken:
    """CAMERA_FEEDBACK: the camera fired (``index`` counts from 1)."""

    index: int
    time_s: float
    lat: float
    lon: float
    alt_msl: float
    alt_rel: float
    roll: float
    pitch: float
    yaw: float


Event = ItemReached | PhotoTaken


class AutoPhase(Enum):
    IDLE = "idle"  # not started (or stopped by leaving AUTO)
    TAKEOFF = "takeoff"
    FLY = "fly"  # to a waypoint's, loiter's or landing's position
    HOLD = "hold"  # at a waypoint for its delay, or loitering for its time
    LAND = "land"
    RTL = "rtl"
    DONE = "done"  # mission complete: hold where it ended


class RtlStage(Enum):
    CLIMB = "climb"
    RETURN = "return"
    LOITER = "loiter"
    LAND = "land"


class Copter:
    """One multirotor: state, the rules for changing it, and the physics that moves it."""

    def __init__(
        self,
        home: GeoPoint,
        params: CopterParams | None = None,
        *,
        system_id: int = 1,
        seed: int = 0,
    ) -> None:
        self.params = params or CopterParams()
        self.param_table = ParamTable(self.params, system_id)
        self.system_id = system_id
        # The EKF origin: local north/east/down are measured from here, and the ground
        # is flat at its altitude.
        self.frame = LocalFrame(home)
        self.body = Airframe()
        self.battery = Battery(capacity_mah=self.params.batt_capacity)
        self.mode = CopterMode.STABILIZE  # ArduCopter's INITIAL_MODE
        self.armed = False
        self.land_complete = True
        self.gps_fix_type = 3
        self.satellites = 10
        self.home_ne = (0.0, 0.0)
        self.battery_failsafe = False
        # the stored mission, item 0 (home) included; empty when there is none
        self.mission: list[MissionItem] = []
        self.mission_current = 0  # the nav command running or to resume; 0: none
        self.photos = 0
        self._events: list[Event] = []
        self._rng = random.Random(seed)
        self.gps_error = (0.0, 0.0, 0.0)  # north, east, up metres of GPS noise

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
        self._low_volt_s = 0.0
        self._auto_phase = AutoPhase.IDLE
        self._auto_item: MissionItem | None = None
        self._auto_next = 0  # where the mission goes on after the current nav command
        self._auto_hold_s = 0.0
        self._cam_trigg_dist = 0.0
        self._cam_last_ne = (0.0, 0.0)

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
        """CRITICAL in a failsafe, else STANDBY while landed (armed or not), ACTIVE in the
        air, as ArduCopter reports."""
        if self.battery_failsafe:
            return MavState.CRITICAL
        return MavState.STANDBY if self.land_complete else MavState.ACTIVE

    def landed_state(self) -> LandedState:
        if self.land_complete:
            return LandedState.ON_GROUND
        if self._landing():
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

    def _landing(self) -> bool:
        """In the descent of LAND, of RTL, or of a mission's NAV_LAND / RTL."""
        rtl_landing = self._rtl_stage is RtlStage.LAND
        if self.mode is CopterMode.AUTO:
            return self._auto_phase is AutoPhase.LAND or (
                self._auto_phase is AutoPhase.RTL and rtl_landing
            )
        return self.mode is CopterMode.LAND or (self.mode is CopterMode.RTL and rtl_landing)

    def drain_events(self) -> list[Event]:
        events, self._events = self._events, []
        return events

    def gps_position(self) -> GeoPoint:
        """What the GPS reports: the true position plus SIM_GPS_NOISE."""
        north, east, up = self.gps_error
        return self.frame.to_global(
            self.body.north + north, self.body.east + east, self.body.alt + up
        )

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

    # -- parameters ------------------------------------------------------------

    def set_param(self, name: str, value: float) -> SetOutcome:
        """PARAM_SET: store ``value`` (MAVLink units) and let it take effect."""
        outcome = self.param_table.set(name, value)
        if outcome is not SetOutcome.STORED:
            return outcome
        old = self.params
        self.params = new = self.param_table.apply(name, old)
        self.battery.capacity_mah = new.batt_capacity
        # AC_WPNav::update_wpnav: a changed WPNAV_SPEED* replaces the speed in use
        if new.wpnav_speed != old.wpnav_speed:
            self._speed_xy = new.wpnav_speed
        if new.wpnav_speed_up != old.wpnav_speed_up:
            self._speed_up = new.wpnav_speed_up
        if new.wpnav_speed_dn != old.wpnav_speed_dn:
            self._speed_down = new.wpnav_speed_dn
        return outcome

    # -- missions --------------------------------------------------------------

    @property
    def mission_count(self) -> int:
        """Mission commands stored after item 0 (home)."""
        return max(0, len(self.mission) - 1)

    def mission_item(self, seq: int) -> MissionItem | None:
        """Item ``seq`` as a GCS downloads it: item 0 is always the current home."""
        if not 0 <= seq < len(self.mission):
            return None
        if seq == 0:
            home = self.home
            return MissionItem(
                0,
                MavFrame.GLOBAL,
                MavCmd.NAV_WAYPOINT,
                x=round(home.lat * 1e7),
                y=round(home.lon * 1e7),
                z=home.alt,
            )
        return self.mission[seq]

    def set_mission(self, items: list[MissionItem]) -> None:
        """Replace the stored mission (a completed upload; item 0 is home)."""
        self.mission = list(items) if len(items) > 1 else []
        if self.mode is CopterMode.AUTO and self._auto_phase is not AutoPhase.IDLE:
            # carry on with the command in flight; the new mission follows it
            self._auto_next = min(self._auto_next, len(self.mission))
            self.mission_current = min(self.mission_current, max(0, len(self.mission) - 1))
        else:
            self.mission_current = 0

    def clear_mission(self) -> bool:
        """MISSION_CLEAR_ALL; refused while the mission is running (AP_Mission::clear)."""
        if self._mission_running():
            return False
        self.mission = []
        self.mission_current = 0
        return True

    def set_mission_current(self, seq: int) -> bool:
        """MISSION_SET_CURRENT: run (or, outside AUTO, resume at) command ``seq``."""
        if not 1 <= seq < len(self.mission):
            return False
        if self._mission_running():
            self._auto_run_from(seq)
        else:
            self.mission_current = seq
        return True

    def mission_state(self) -> MissionState:
        """MISSION_CURRENT.mission_state, as ArduPilot 4.5 reports it."""
        if self.mission_count == 0:
            return MissionState.NO_MISSION
        if self._auto_phase is AutoPhase.DONE:
            return MissionState.COMPLETE
        if self.mode is CopterMode.AUTO and self._auto_phase is not AutoPhase.IDLE:
            return MissionState.ACTIVE
        return MissionState.NOT_STARTED if self.mission_current == 0 else MissionState.PAUSED

    def _mission_running(self) -> bool:
        return (
            self.mode is CopterMode.AUTO
            and self.armed
            and self._auto_phase not in (AutoPhase.IDLE, AutoPhase.DONE)
        )

    def _first_nav_seq(self) -> int | None:
        start = self.mission_current if self.mission_current >= 1 else 1
        for seq in range(start, len(self.mission)):
            if self.mission[seq].is_nav:
                return seq
        return None

    def _mission_starts_with_takeoff(self) -> bool:
        seq = self._first_nav_seq()
        return seq is not None and self.mission[seq].command == MavCmd.NAV_TAKEOFF

    def _item_alt(self, item: MissionItem) -> float:
        """A mission item's altitude above home."""
        if item.frame in ABSOLUTE_FRAMES:
            return item.z - self.home.alt
        return item.z

    def _item_ne(self, item: MissionItem) -> tuple[float, float]:
        """A mission item's position; none given (0, 0) means where the vehicle is."""
        if not item.has_position:
            return self.body.stopping_point(self.params.wpnav_accel)
        return self.frame.to_local(item.x / 1e7, item.y / 1e7)

    def _auto_begin(self) -> None:
        """ModeAuto::run with a mission not yet started: start or resume it."""
        self._auto_run_from(self.mission_current if self.mission_current >= 1 else 1)

    def _auto_run_from(self, seq: int) -> None:
        """Run "do" commands up to the next nav command, start that, and then the "do"
        commands after it, which ArduPilot runs while the nav command is in progress."""
        mission = self.mission
        while seq < len(mission) and not mission[seq].is_nav:
            self._do_command(mission[seq])
            seq += 1
        if seq >= len(mission):
            self._auto_complete()
            return
        self.mission_current = seq
        self._start_nav(mission[seq])
        following = seq + 1
        while following < len(mission) and not mission[following].is_nav:
            self._do_command(mission[following])
            following += 1
        self._auto_next = following

    def _auto_complete(self) -> None:
        """ModeAuto::exit_mission: hold where it is (disarms if on the ground)."""
        self._auto_item = None
        self._auto_phase = AutoPhase.DONE
        self._hold_ne = self.body.stopping_point(self.params.wpnav_accel)
        self._hold_alt = self._stopping_alt()
        self._say(Severity.INFO, "Mission complete")
        if self.armed and self.land_complete:
            self._disarm()

    def _nav_done(self) -> None:
        item = self._auto_item
        if item is not None:
            self._events.append(ItemReached(item.seq))
        self._auto_run_from(self._auto_next)

    def _start_nav(self, item: MissionItem) -> None:
        self._auto_item = item
        self._auto_hold_s = 0.0
        match item.command:
            case MavCmd.NAV_TAKEOFF:
                self._auto_phase = AutoPhase.TAKEOFF
                alt = max(self._item_alt(item), self.body.alt)
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
                self._hold_alt = alt if alt != 0.0 or item.has_position else self.body.alt
                self._auto_phase = AutoPhase.FLY

    def _do_command(self, item: MissionItem) -> None:
        match item.command:
            case MavCmd.DO_CHANGE_SPEED:
                self.set_guided_speed(int(item.param1), item.param2)
            case MavCmd.DO_SET_CAM_TRIGG_DIST:
                self._cam_trigg_dist = max(0.0, item.param1)
                self._cam_last_ne = (self.body.north, self.body.east)
                if item.param3 == 1.0:
                    self.take_photo()
            case MavCmd.DO_DIGICAM_CONTROL:
                if item.x == 1:  # param5 "shot"
                    self.take_photo()

    def take_photo(self) -> None:
        """AP_Camera::take_picture: the shutter fires; CAMERA_FEEDBACK follows."""
        self.photos += 1
        point = self.position()
        body = self.body
        self._cam_last_ne = (body.north, body.east)
        self._events.append(
            PhotoTaken(
                self.photos,
                self.time_s,
                point.lat,
                point.lon,
                point.alt,
                self.relative_alt,
                body.roll,
                body.pitch,
                body.yaw,
            )
        )

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

    # -- fault injection (tests, demo) -----------------------------------------

    def set_gps_fix(self, fix_type: int, satellites: int | None = None) -> None:
        self.gps_fix_type = fix_type
        self.satellites = satellites if satellites is not None else (10 if fix_type >= 3 else 0)

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
        self._check_camera_distance()
        if self._steps % GPS_PERIOD_STEPS == 0:
            sigma = p.sim_gps_noise
            gauss = self._rng.gauss
            self.gps_error = (gauss(0.0, sigma), gauss(0.0, sigma), gauss(0.0, 1.5 * sigma))
        self._steps += 1

    def _check_camera_distance(self) -> None:
        """AP_Camera: with a trigger distance set, a photo every that many metres flown."""
        if self._cam_trigg_dist <= 0.0 or not self.flying:
            return
        here = (self.body.north, self.body.east)
        if math.dist(here, self._cam_last_ne) >= self._cam_trigg_dist:
            self.take_photo()

    def _check_battery(self) -> None:
        """AP_BattMonitor::check_failsafes and Copter::handle_battery_failsafe."""
        p = self.params
        if self.battery_failsafe or not self.armed:
            self._low_volt_s = 0.0
            return
        battery = self.battery
        low_volt = p.batt_low_volt > 0.0 and battery.voltage < p.batt_low_volt
        self._low_volt_s = self._low_volt_s + DT if low_volt else 0.0
        volt_trip = low_volt and self._low_volt_s + 1e-9 >= p.batt_low_timer
        mah_trip = p.batt_low_mah > 0.0 and battery.remaining_mah < p.batt_low_mah
        if not (volt_trip or mah_trip):
            return
        self.battery_failsafe = True
        self._say(
            Severity.WARNING,
            f"Battery 1 is low {battery.voltage:.2f}V used {battery.consumed_mah:.0f} mAh",
        )
        if p.batt_fs_low_act == 0:
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
