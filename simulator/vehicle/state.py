"""A vehicle's state: sim time in fixed physics steps, the GPS and battery, home, the
parameters, and what it is on the wire."""

from __future__ import annotations

import math
import random
from abc import ABC, abstractmethod
from enum import Enum, IntEnum
from typing import TypeVar

from common.geodesy import GeoPoint, LocalFrame
from simulator.mavconst import LandedState, MavResult, MavState, Severity
from simulator.params.table import ParamTable, SetOutcome
from simulator.params.values import CopterParams
from simulator.vehicle.battery import Battery
from simulator.vehicle.events import Event, StatusText
from simulator.vehicle.physics import Airframe
from simulator.vehicle.stored_mission import MissionItem

DT = 0.02  # physics step, sim seconds
GPS_PERIOD_STEPS = 10  # a GPS fix every 0.2 s (5 Hz), each with fresh noise
_STEP_EPSILON = 1e-6  # in steps: absorbs float error when summing many small increments
# Sim seconds a new 3D fix must hold before the EKF uses it (AP_NavEKF3's GPS checks
# pass for 10 s first): until then arming and take-off that need a position are refused.
EKF_GPS_DELAY_S = 10.0
# AP_AHRS::set_home refuses a home this far from the EKF origin (Copter::far_from_EKF_origin).
FAR_FROM_ORIGIN_M = 50_000.0


class AutoPhase(Enum):
    IDLE = "idle"  # not started (or stopped by leaving AUTO)
    TAKEOFF = "takeoff"
    FLY = "fly"  # to a waypoint's, loiter's or landing's position
    HOLD = "hold"  # at a waypoint for its delay, or loitering for its time
    LAND = "land"
    RTL = "rtl"
    DONE = "done"  # mission complete: hold where it ended


ModeT = TypeVar("ModeT", bound=IntEnum)


class VehicleState(ABC):
    """One simulated vehicle's state: sensors, home, mission and parameters, in sim time.

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
        # The newest MANUAL_CONTROL from the GCS (x, y, z, r) and when it came (sim s).
        self._sticks: tuple[int, int, int, int] | None = None
        self._sticks_at = 0.0
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

    @property
    def mission_wire_offset(self) -> int:
        """How far the stored mission's numbers (home first) are from the wire's."""
        return 0

    @property
    def param_bytewise(self) -> bool:
        """Integer parameters travel bytewise (PX4), not cast to float (ArduPilot)."""
        return False

    def takes_manual_control(self, sender: int) -> bool:
        """GCS_MAVLINK::handle_manual_control: only from SYSID_MYGCS, else ignored."""
        return sender == self.params.sysid_mygcs

    def manual_control(self, x: int, y: int, z: int, r: int) -> None:
        """MANUAL_CONTROL from the GCS, already checked against SYSID_MYGCS: an RC
        override of pitch (x), roll (y), throttle (z, 0..1000) and yaw (r)."""
        self._sticks = (x, y, z, r)
        self._sticks_at = self.time_s

    def overridden_sticks(self) -> tuple[int, int, int, int] | None:
        """The GCS's sticks while fresh: RC_OVERRIDE_TIME after the last one they lapse
        and the transmitter's rule again (the personality's); a negative time never lapses."""
        timeout = self.params.rc_override_time
        if self._sticks is None or (0 <= timeout < self.time_s - self._sticks_at):
            return None
        return self._sticks

    def position_frame_ok(self, frame: int) -> bool:
        """Whether a COMMAND_INT reposition or set-home in ``frame`` is taken at all
        (ArduPilot converts every global frame; a personality may be stricter)."""
        return True
