"""What every simulated vehicle shares, whatever it is and whichever autopilot it plays.

Sim time in fixed physics steps, the GPS and battery, home, the stored mission and how a
mission is walked through, the parameters, the camera, STATUSTEXTs and events, and what
a reboot keeps. `Copter` and `Rover` add their autopilot's rules and their motion. Pure
logic, no I/O and no wall clock: time moves only through `advance`/`advance_to`.
"""

from __future__ import annotations

import math
import random
from abc import ABC, abstractmethod
from dataclasses import dataclass
from enum import Enum, IntEnum
from typing import Self, TypeVar

from common.geodesy import GeoPoint, LocalFrame
from simulator.battery import Battery
from simulator.mavconst import (
    LandedState,
    MavCmd,
    MavFrame,
    MavResult,
    MavState,
    MissionState,
    Severity,
)
from simulator.mission import ABSOLUTE_FRAMES, MissionItem
from simulator.param_table import ParamTable, SetOutcome
from simulator.params import CopterParams
from simulator.physics import Airframe

DT = 0.02  # physics step, sim seconds
GPS_PERIOD_STEPS = 10  # a GPS fix every 0.2 s (5 Hz), each with fresh noise
_STEP_EPSILON = 1e-6  # in steps: absorbs float error when summing many small increments
# Sim seconds a new 3D fix must hold before the EKF uses it (AP_NavEKF3's GPS checks
# pass for 10 s first): until then arming and take-off that need a position are refused.
EKF_GPS_DELAY_S = 10.0
# AP_AHRS::set_home refuses a home this far from the EKF origin (Copter::far_from_EKF_origin).
FAR_FROM_ORIGIN_M = 50_000.0


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


ModeT = TypeVar("ModeT", bound=IntEnum)


class Vehicle(ABC):
    """One simulated vehicle: sensors, home, mission and parameters, stepped in sim time.

    ``boot_at`` is the reading of the sim clock at which this vehicle booted, so that a
    vehicle rebooted mid-run counts its own time from zero (TIME_BOOT_MS starts again).
    """

    mode: IntEnum  # the autopilot's own mode number (ArduCopter's, ArduRover's)

    def __init__(
        self,
        home: GeoPoint,
        params: CopterParams | None = None,
        *,
        system_id: int = 1,
        seed: int = 0,
        boot_at: float = 0.0,
    ) -> None:
        self.params = params or CopterParams()
        self.param_table = self._new_param_table(self.params, system_id)
        self.system_id = system_id
        self.seed = seed
        self.boot_at = boot_at
        # The EKF origin: local north/east/down are measured from here, and the ground
        # is flat at its altitude.
        self.frame = LocalFrame(home.lat, home.lon, home.alt)
        self.body = Airframe()
        self.battery = Battery(capacity_mah=self.params.batt_capacity)
        self.armed = False
        self.gps_fix_type = 3
        # when the 3D fix came; at boot the EKF has long been using it
        self._fix_since: float | None = -EKF_GPS_DELAY_S
        self.satellites = 10
        self.home_ne = (0.0, 0.0)
        self.home_up = 0.0  # home's height above the ground at the origin
        self.home_locked = False  # set by a GCS: arming no longer moves it
        self.battery_failsafe = False
        self.reboot_requested = False  # accepted: the transport restarts the vehicle
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
        self._low_volt_s = 0.0
        self._auto_phase = AutoPhase.IDLE
        self._auto_item: MissionItem | None = None
        self._auto_next = 0  # where the mission goes on after the current nav command
        self._auto_hold_s = 0.0
        self._cam_trigg_dist = 0.0
        self._cam_last_ne = (0.0, 0.0)

    def _new_param_table(self, params: CopterParams, system_id: int) -> ParamTable:
        return ParamTable(params, system_id)

    # -- what the vehicle is ---------------------------------------------------

    @property
    @abstractmethod
    def mav_type(self) -> int:
        """HEARTBEAT.type."""

    @property
    @abstractmethod
    def autopilot(self) -> int:
        """HEARTBEAT.autopilot."""

    @abstractmethod
    def base_mode(self) -> int:
        """HEARTBEAT.base_mode."""

    @abstractmethod
    def custom_mode(self) -> int:
        """HEARTBEAT.custom_mode, in the autopilot's encoding."""

    @abstractmethod
    def system_status(self) -> MavState: ...

    @abstractmethod
    def landed_state(self) -> LandedState: ...

    @abstractmethod
    def prearm_ok(self) -> bool:
        """Whether the pre-arm checks pass in the current mode (SYS_STATUS PREARM bit)."""

    @property
    @abstractmethod
    def manual_mode(self) -> bool:
        """In a mode without position and altitude control (SYS_STATUS reports them off)."""

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
        """Catch up with a clock reading ``sim_time`` sim seconds (since ``boot_at``)."""
        since_boot = sim_time - self.boot_at
        if since_boot > self._target_time:
            self._target_time = since_boot
            self._run_due_steps()

    def _run_due_steps(self) -> None:
        due = math.floor(self._target_time / DT + _STEP_EPSILON)
        while self._steps < due:
            self._step()
            self._steps += 1

    @abstractmethod
    def _step(self) -> None:
        """One physics step of `DT` sim seconds."""

    def _step_sensors(self) -> None:
        """The parts of a step every vehicle has: camera, GPS noise."""
        self._check_camera_distance()
        if self._steps % GPS_PERIOD_STEPS == 0:
            sigma = self.params.sim_gps_noise
            gauss = self._rng.gauss
            self.gps_error = (gauss(0.0, sigma), gauss(0.0, sigma), gauss(0.0, 1.5 * sigma))

    # -- derived state -----------------------------------------------------

    @property
    def position_ok(self) -> bool:
        """The EKF has an absolute position: a 3D fix, in use once it has held for
        EKF_GPS_DELAY_S (ArduPilot's EKF takes the GPS after 10 s of good fixes)."""
        since = self._fix_since
        return (
            self.gps_fix_type >= 3
            and since is not None
            and self.time_s - since + 1e-9 >= EKF_GPS_DELAY_S
        )

    @property
    def home(self) -> GeoPoint:
        return self.geo_of(north=self.home_ne[0], east=self.home_ne[1], up=self.home_up)

    def position(self) -> GeoPoint:
        return self.geo_of(north=self.body.north, east=self.body.east, up=self.body.alt)

    def geo_of(self, *, north: float, east: float, up: float = 0.0) -> GeoPoint:
        """The position `north`/`east` metres from the EKF origin and `up` above it. By
        keyword: the simulator keeps ArduPilot's north-east order, common.geodesy's frames
        east-north."""
        lat, lon = self.frame.to_geo(east, north)
        return GeoPoint(lat, lon, self.frame.origin.alt + up)

    def ne_of(self, lat: float, lon: float) -> tuple[float, float]:
        """(north, east) metres of a position from the EKF origin, in the simulator's order."""
        east, north = self.frame.to_local(lat, lon)
        return north, east

    @property
    def altitude_msl(self) -> float:
        return self.frame.origin.alt + self.body.alt

    @property
    def relative_alt(self) -> float:
        """Metres above home."""
        return self.body.alt - self.home_up

    def gps_position(self) -> GeoPoint:
        """What the GPS reports: the true position plus SIM_GPS_NOISE."""
        north, east, up = self.gps_error
        return self.geo_of(
            north=self.body.north + north, east=self.body.east + east, up=self.body.alt + up
        )

    def drain_events(self) -> list[Event]:
        events, self._events = self._events, []
        return events

    def drain_texts(self) -> list[StatusText]:
        texts, self._texts = self._texts, []
        return texts

    def _requested_mode(
        self, number: int, modes: type[ModeT], supported: frozenset[ModeT]
    ) -> ModeT | None:
        """The mode a GCS asked for by number, or None once the refusal has been said."""
        try:
            mode = modes(number)
        except ValueError:
            self._say(Severity.WARNING, f"No such mode {number}")
            return None
        if mode not in supported:
            self._say(Severity.WARNING, f"Mode change to {mode.name} failed: not simulated")
            return None
        return mode

    def _say(self, severity: Severity, text: str) -> None:
        self._texts.append(StatusText(severity, text))

    # -- commands every vehicle answers ---------------------------------------

    @abstractmethod
    def arm(self, force: bool = False) -> MavResult:
        """MAV_CMD_COMPONENT_ARM_DISARM param1=1; ``force`` is param2=2989."""

    @abstractmethod
    def disarm(self, force: bool = False) -> MavResult:
        """MAV_CMD_COMPONENT_ARM_DISARM param1=0; ``force`` is param2=21196."""

    @abstractmethod
    def set_mode(self, number: int) -> MavResult:
        """A mode change to the autopilot's own mode number."""

    @abstractmethod
    def request_mode(self, base_mode: int, custom_mode: int, custom_sub_mode: int) -> MavResult:
        """MAV_CMD_DO_SET_MODE, in the autopilot's encoding."""

    @abstractmethod
    def request_mode_encoded(self, base_mode: int, custom_mode: int) -> MavResult:
        """SET_MODE: custom_mode as HEARTBEAT carries it."""

    @abstractmethod
    def nav_takeoff(self, altitude: float, frame: int) -> MavResult:
        """MAV_CMD_NAV_TAKEOFF from a GCS."""

    @abstractmethod
    def nav_land(self) -> MavResult:
        """MAV_CMD_NAV_LAND from a GCS."""

    @abstractmethod
    def return_to_launch(self) -> MavResult:
        """MAV_CMD_NAV_RETURN_TO_LAUNCH from a GCS."""

    @abstractmethod
    def change_speed(self, kind: int, speed: float) -> MavResult:
        """MAV_CMD_DO_CHANGE_SPEED: param1 speed type, param2 m/s."""

    @property
    @abstractmethod
    def in_guided(self) -> bool:
        """Whether position targets from a GCS are flown now."""

    @abstractmethod
    def enter_guided(self) -> MavResult:
        """Switch to the mode that flies position targets (DO_REPOSITION's change of mode)."""

    @abstractmethod
    def guided_goto(self, lat: float, lon: float, relative_alt: float) -> MavResult:
        """Go to a position while in guided."""

    @abstractmethod
    def guided_hold(self) -> None:
        """Re-initialise guided to hold position (what ArduPilot does on a bad target)."""

    @property
    def reboot_declined(self) -> MavResult:
        """The answer to MAV_CMD_PREFLIGHT_REBOOT_SHUTDOWN while armed (ArduPilot's
        handle_preflight_reboot: FAILED, without a STATUSTEXT)."""
        return MavResult.FAILED

    def request_reboot(self, action: float, force: bool) -> MavResult:
        """MAV_CMD_PREFLIGHT_REBOOT_SHUTDOWN (GCS_MAVLINK::handle_preflight_reboot):
        param1 1 reboots (3, into the bootloader, is not simulated); refused while armed
        unless forced (param6 20190226). Accepted, the transport answers first and then
        restarts the vehicle (`rebooted`), as ArduPilot acknowledges before it resets."""
        if action != 1.0:
            return MavResult.UNSUPPORTED
        if self.armed and not force:
            return self.reboot_declined
        self.reboot_requested = True
        return MavResult.ACCEPTED

    # -- home ------------------------------------------------------------------

    def set_home_here(self) -> MavResult:
        """MAV_CMD_DO_SET_HOME param1=1 (set_home_to_current_location(lock=true)):
        the position *and altitude* the vehicle is at, locked."""
        if not self.position_ok:
            return MavResult.FAILED
        self._move_home(self.body.north, self.body.east, self.body.alt)
        self.home_locked = True
        return MavResult.ACCEPTED

    def set_home_to(self, lat: float, lon: float, alt_msl: float) -> MavResult:
        """MAV_CMD_DO_SET_HOME param1=0: a given point, locked (Copter::set_home);
        refused far from the EKF origin."""
        if not (-90.0 <= lat <= 90.0 and -180.0 <= lon <= 180.0) or not math.isfinite(alt_msl):
            return MavResult.DENIED
        north, east = self.ne_of(lat, lon)
        if math.hypot(north, east) > FAR_FROM_ORIGIN_M:
            return MavResult.FAILED
        self._move_home(north, east, alt_msl - self.frame.origin.alt)
        self.home_locked = True
        return MavResult.ACCEPTED

    def _move_home(self, north: float, east: float, up: float) -> None:
        self.home_ne = (north, east)
        self.home_up = up

    def _home_on_arming(self) -> None:
        """Home follows the vehicle to where it arms unless a GCS has locked it."""
        if not self.home_locked and self.body.on_ground:
            self._move_home(self.body.north, self.body.east, 0.0)

    def _relative_to_origin(self, relative_alt: float) -> float:
        """An altitude above home as height above the ground at the origin."""
        return relative_alt + self.home_up

    # -- parameters ------------------------------------------------------------

    def set_param(self, name: str, value: float) -> SetOutcome:
        """PARAM_SET: store ``value`` (MAVLink units) and let it take effect."""
        outcome = self.param_table.set(name, value)
        if outcome is not SetOutcome.STORED:
            return outcome
        old = self.params
        self.params = new = self.param_table.apply(name, old)
        self.battery.capacity_mah = new.batt_capacity
        self._params_changed(old, new)
        return outcome

    def _params_changed(self, old: CopterParams, new: CopterParams) -> None:
        """Let changed parameters take effect beyond what is read on every step."""
        return  # nothing to do by default

    # -- battery ---------------------------------------------------------------

    def _battery_low(self) -> bool:
        """AP_BattMonitor::check_failsafes: BATT_LOW_VOLT for BATT_LOW_TIMER, or
        BATT_LOW_MAH; reports the failsafe once, the moment it trips."""
        p = self.params
        if self.battery_failsafe or not self.armed:
            self._low_volt_s = 0.0
            return False
        battery = self.battery
        low_volt = p.batt_low_volt > 0.0 and battery.voltage < p.batt_low_volt
        self._low_volt_s = self._low_volt_s + DT if low_volt else 0.0
        volt_trip = low_volt and self._low_volt_s + 1e-9 >= p.batt_low_timer
        mah_trip = p.batt_low_mah > 0.0 and battery.remaining_mah < p.batt_low_mah
        if not (volt_trip or mah_trip):
            return False
        self.battery_failsafe = True
        self._say(
            Severity.WARNING,
            f"Battery 1 is low {battery.voltage:.2f}V used {battery.consumed_mah:.0f} mAh",
        )
        return True

    # -- fault injection (tests, demo) -----------------------------------------

    def set_gps_fix(self, fix_type: int, satellites: int | None = None) -> None:
        if fix_type < 3:
            self._fix_since = None
        elif self.gps_fix_type < 3:
            self._fix_since = self.time_s  # the EKF starts its wait for a steady fix
        self.gps_fix_type = fix_type
        self.satellites = satellites if satellites is not None else (10 if fix_type >= 3 else 0)

    # -- missions --------------------------------------------------------------

    @property
    @abstractmethod
    def in_auto(self) -> bool:
        """In the mode that runs the stored mission."""

    @property
    def mission_wire_offset(self) -> int:
        """How far the stored mission's numbers (home first) are from the wire's."""
        return 0

    @property
    def param_bytewise(self) -> bool:
        """Integer parameters travel bytewise (PX4), not cast to float (ArduPilot)."""
        return False

    def position_frame_ok(self, frame: int) -> bool:
        """Whether a COMMAND_INT reposition or set-home in ``frame`` is taken at all
        (ArduPilot converts every global frame; a personality may be stricter)."""
        return True

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
        if self.in_auto and self._auto_phase is not AutoPhase.IDLE:
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
        if self.in_auto and self._auto_phase is not AutoPhase.IDLE:
            return MissionState.ACTIVE
        return MissionState.NOT_STARTED if self.mission_current == 0 else MissionState.PAUSED

    def _mission_running(self) -> bool:
        return (
            self.in_auto and self.armed and self._auto_phase not in (AutoPhase.IDLE, AutoPhase.DONE)
        )

    def _first_nav_seq(self) -> int | None:
        start = self.mission_current if self.mission_current >= 1 else 1
        for seq in range(start, len(self.mission)):
            if self.mission[seq].is_nav:
                return seq
        return None

    def _item_alt(self, item: MissionItem) -> float:
        """A mission item's altitude above home."""
        if item.frame in ABSOLUTE_FRAMES:
            return item.z - self.home.alt
        return item.z

    def _item_ne(self, item: MissionItem) -> tuple[float, float]:
        """A mission item's position; none given (0, 0) means where the vehicle stops."""
        if not item.has_position:
            return self.body.stopping_point(self.params.wpnav_accel)
        return self.ne_of(item.x / 1e7, item.y / 1e7)

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

    def _nav_done(self) -> None:
        item = self._auto_item
        if item is not None:
            self._events.append(ItemReached(item.seq))
        self._auto_run_from(self._auto_next)

    @abstractmethod
    def _start_nav(self, item: MissionItem) -> None:
        """Begin a navigation command."""

    @abstractmethod
    def _auto_complete(self) -> None:
        """The mission has run out of commands (ModeAuto::exit_mission)."""

    def _do_command(self, item: MissionItem) -> None:
        match item.command:
            case MavCmd.DO_CHANGE_SPEED:
                self.change_speed(int(item.param1), item.param2)
            case MavCmd.DO_SET_CAM_TRIGG_DIST:
                self._cam_trigg_dist = max(0.0, item.param1)
                self._cam_last_ne = (self.body.north, self.body.east)
                if item.param3 == 1.0:
                    self.take_photo()
            case MavCmd.DO_DIGICAM_CONTROL:
                if item.x == 1:  # param5 "shot"
                    self.take_photo()

    # -- camera ----------------------------------------------------------------

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

    @property
    def _camera_moving(self) -> bool:
        return self.armed

    def _check_camera_distance(self) -> None:
        """AP_Camera: with a trigger distance set, a photo every that many metres moved."""
        if self._cam_trigg_dist <= 0.0 or not self._camera_moving:
            return
        here = (self.body.north, self.body.east)
        if math.dist(here, self._cam_last_ne) >= self._cam_trigg_dist:
            self.take_photo()

    # -- reboot ----------------------------------------------------------------

    def rebooted(self, boot_at: float) -> Self:
        """The same vehicle after its flight controller restarts (refused while armed,
        so it is not flying): what the board stores survives (parameters, the mission),
        and so does the physical world (where it stands, its battery); everything else
        starts again: the initial mode, a new EKF origin where it is, home not yet
        locked, sim time from zero."""
        here = self.position()
        twin = self._reborn(GeoPoint(here.lat, here.lon, self.frame.origin.alt), boot_at)
        twin.params = self.params
        twin.param_table = self.param_table
        twin.battery = self.battery
        twin.mission = list(self.mission)
        twin.body.down = self.body.down
        twin.body.yaw = self.body.yaw
        twin.gps_fix_type, twin.satellites = self.gps_fix_type, self.satellites
        if self.gps_fix_type >= 3 and not self.position_ok:  # still waiting: from its boot
            twin._fix_since = twin.time_s
        elif self.gps_fix_type < 3:
            twin._fix_since = None
        return twin

    @abstractmethod
    def _reborn(self, origin: GeoPoint, boot_at: float) -> Self:
        """A freshly booted vehicle of the same kind, its EKF origin at ``origin``."""
