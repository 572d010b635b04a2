"""The simulated ground vehicle: ArduRover's modes, arming and mission rules, on wheels.

Pure logic, like `Copter`. Behaviour follows ArduRover 4.x (Rover/mode*.cpp,
GCS_MAVLink_Rover.cpp, AP_Arming_Rover.cpp):

* it starts in MANUAL; with no RC input MANUAL and HOLD stand still; AUTO drives the
  mission, GUIDED drives to position targets, RTL drives home and stops there;
* it arms in any mode, AUTO included, needing a 3D fix only in the modes that navigate
  (AUTO, GUIDED, RTL), and disarms whenever asked: on the ground there is no "in flight";
* MAV_CMD_NAV_TAKEOFF and NAV_LAND are not Rover commands (MAV_RESULT_UNSUPPORTED); in a
  mission they are skipped ("Skipping invalid cmd #22"), as ModeAuto::verify_command does;
* DO_CHANGE_SPEED works in AUTO, GUIDED and RTL; a climb or descent speed is DENIED;
* a finished mission stops the rover and leaves it in AUTO ("Mission Complete", the
  default MIS_DONE_BEHAVE); HEARTBEAT says STANDBY only in HOLD, ACTIVE otherwise, and
  EXTENDED_SYS_STATE's landed state is UNDEFINED, as Rover reports them.
"""

from __future__ import annotations

import dataclasses
import math
import struct
from typing import Self

from common.geodesy import GeoPoint
from simulator.mavconst import (
    SUPPORTED_ROVER_MODES,
    LandedState,
    MavAutopilot,
    MavCmd,
    MavResult,
    MavState,
    MavType,
    ModeFlag,
    RoverMode,
    Severity,
)
from simulator.params.table import ParamDef, ParamTable, ParamType
from simulator.params.values import CopterParams
from simulator.vehicle import DT, AutoPhase, Vehicle
from simulator.vehicle.battery import current_draw
from simulator.vehicle.physics import Setpoint
from simulator.vehicle.stored_mission import MissionItem

# Rover's defaults for what the shared parameter fields mean on a rover.
ROVER_DEFAULTS = dataclasses.replace(
    CopterParams(),
    wpnav_speed=2.0,  # WP_SPEED
    wpnav_accel=1.0,  # ATC_ACCEL_MAX
    wpnav_radius=2.0,  # WP_RADIUS
)

# ArduRover's names (alphabetical, as ArduPilot indexes them) for the parameters the
# rover honours, on the same fields the copter uses.
ROVER_PARAM_DEFS: tuple[ParamDef, ...] = (
    ParamDef("ATC_ACCEL_MAX", ParamType.REAL32, 0, 10, "wpnav_accel"),
    ParamDef("BATT_CAPACITY", ParamType.INT32, 100, 1_000_000, "batt_capacity"),
    ParamDef("BATT_FS_LOW_ACT", ParamType.INT8, 0, 2, "batt_fs_low_act"),
    ParamDef("BATT_LOW_MAH", ParamType.REAL32, 0, 1_000_000, "batt_low_mah"),
    ParamDef("BATT_LOW_TIMER", ParamType.INT8, 0, 120, "batt_low_timer"),
    ParamDef("BATT_LOW_VOLT", ParamType.REAL32, 0, 100, "batt_low_volt"),
    ParamDef("SIM_BATT_DRAIN", ParamType.REAL32, 0.0, 1000.0, "sim_batt_drain"),
    ParamDef("SIM_GPS_NOISE", ParamType.REAL32, 0.0, 100.0, "sim_gps_noise"),
    # ArduRover takes MANUAL_CONTROL only from its GCS too (handle_manual_control)
    ParamDef("SYSID_MYGCS", ParamType.INT16, 1, 255, "sysid_mygcs"),
    ParamDef("SYSID_THISMAV", ParamType.INT16, 1, 255),
    ParamDef("WP_RADIUS", ParamType.REAL32, 0, 1000, "wpnav_radius"),
    ParamDef("WP_SPEED", ParamType.REAL32, 0, 100, "wpnav_speed"),
)

# Modes that navigate, and so need a position to arm in or switch to while armed
# (Mode::requires_position: false for MANUAL, ACRO, STEERING and HOLD).
_POSITION_MODES = frozenset({RoverMode.AUTO, RoverMode.GUIDED, RoverMode.RTL})
# Modes with a pilot behind the sticks (Mode::has_manual_input).
_MANUAL_INPUT_MODES = frozenset({RoverMode.MANUAL, RoverMode.ACRO, RoverMode.STEERING})
# Modes in which DO_CHANGE_SPEED sets the speed (Mode::set_desired_speed).
_SPEED_MODES = frozenset({RoverMode.AUTO, RoverMode.GUIDED, RoverMode.RTL})
_SPEED_TYPE_CLIMB, _SPEED_TYPE_DESCENT = 2, 3


class RoverParamTable(ParamTable):
    """The rover's parameters under ArduRover's names: the same table, other entries."""

    def __init__(self, params: CopterParams, system_id: int) -> None:
        super().__init__(params, system_id)
        self._defs = {d.name: d for d in ROVER_PARAM_DEFS}
        self._names = [d.name for d in ROVER_PARAM_DEFS]
        self._values = {d.name: _initial_value(d, params, system_id) for d in ROVER_PARAM_DEFS}


def _initial_value(definition: ParamDef, params: CopterParams, system_id: int) -> float:
    """A parameter's value at boot in MAVLink units, as PARAM_VALUE's float32 carries it."""
    if definition.field is not None:
        value = float(getattr(params, definition.field)) / definition.scale
    elif definition.name == "SYSID_THISMAV":
        value = float(system_id)
    else:
        value = float(definition.default or 0.0)
    return float(struct.unpack("<f", struct.pack("<f", value))[0])


class Rover(Vehicle):
    """One wheeled ground vehicle playing ArduRover."""

    mode: RoverMode

    def __init__(
        self,
        home: GeoPoint,
        params: CopterParams | None = None,
        *,
        system_id: int = 1,
        seed: int = 0,
        boot_at: float = 0.0,
    ) -> None:
        super().__init__(
            home, params or ROVER_DEFAULTS, system_id=system_id, seed=seed, boot_at=boot_at
        )
        self.mode = RoverMode.MANUAL  # Rover's INITIAL_MODE
        self._target_ne: tuple[float, float] | None = None  # None: stop
        self._speed = self.params.wpnav_speed

    def _new_param_table(self, params: CopterParams, system_id: int) -> ParamTable:
        return RoverParamTable(params, system_id)

    def _reborn(self, origin: GeoPoint, boot_at: float) -> Self:
        return type(self)(
            origin, self.params, system_id=self.system_id, seed=self.seed, boot_at=boot_at
        )

    # -- what the vehicle is -----------------------------------------------

    @property
    def mav_type(self) -> int:
        return int(MavType.GROUND_ROVER)

    @property
    def autopilot(self) -> int:
        return int(MavAutopilot.ARDUPILOTMEGA)

    def base_mode(self) -> int:
        """GCS_MAVLINK_Rover::base_mode."""
        flags = ModeFlag.CUSTOM_MODE_ENABLED
        if self.mode in _MANUAL_INPUT_MODES:
            flags |= ModeFlag.MANUAL_INPUT_ENABLED
        if self.mode in _POSITION_MODES:  # is_autopilot_mode
            flags |= ModeFlag.GUIDED_ENABLED
        if self.armed:
            flags |= ModeFlag.SAFETY_ARMED
        return int(flags)

    def custom_mode(self) -> int:
        return int(self.mode)

    def system_status(self) -> MavState:
        """GCS_MAVLINK_Rover::vehicle_system_status."""
        if self.battery_failsafe:
            return MavState.CRITICAL
        return MavState.STANDBY if self.mode is RoverMode.HOLD else MavState.ACTIVE

    def landed_state(self) -> LandedState:
        return LandedState.UNDEFINED  # Rover does not report one

    def prearm_ok(self) -> bool:
        return self.position_ok or self.mode not in _POSITION_MODES

    @property
    def manual_mode(self) -> bool:
        return self.mode not in _POSITION_MODES

    @property
    def in_guided(self) -> bool:
        return self.mode is RoverMode.GUIDED

    @property
    def in_auto(self) -> bool:
        return self.mode is RoverMode.AUTO

    # -- commands ----------------------------------------------------------

    def arm(self, force: bool = False) -> MavResult:
        """AP_Arming_Rover::arm: only a navigating mode needs a position, even forced."""
        if self.armed:
            return MavResult.ACCEPTED
        if self.mode in _POSITION_MODES and not self.position_ok:
            self._say(Severity.CRITICAL, "Arm: GPS 1: Bad fix")
            return MavResult.FAILED
        self.armed = True
        self._home_on_arming()
        self._say(Severity.INFO, "Throttle armed")
        return MavResult.ACCEPTED

    def disarm(self, force: bool = False) -> MavResult:
        if self.armed:
            self.armed = False
            self._say(Severity.INFO, "Throttle disarmed")
        return MavResult.ACCEPTED

    def set_mode(self, number: int) -> MavResult:
        """Rover::set_mode for a GCS request."""
        if number == self.mode:
            return MavResult.ACCEPTED
        mode = self._requested_mode(number, RoverMode, SUPPORTED_ROVER_MODES)
        if mode is None:
            return MavResult.FAILED
        if mode is RoverMode.AUTO and self.mission_count == 0:
            self._say(Severity.NOTICE, "No Mission. Can't set AUTO.")  # ModeAuto::_enter
            self._say(Severity.WARNING, "Flight mode change failed")
            return MavResult.FAILED
        if self.armed and mode in _POSITION_MODES and not self.position_ok:
            self._say(Severity.WARNING, "Flight mode change failed")
            return MavResult.FAILED
        self._enter_mode(mode)
        return MavResult.ACCEPTED

    def _enter_mode(self, mode: RoverMode) -> None:
        self.mode = mode
        self._auto_phase = AutoPhase.IDLE
        self._speed = self.params.wpnav_speed  # AR_WPNav::init: the default speed again
        self._target_ne = None  # every mode starts by stopping
        if mode is RoverMode.GUIDED:
            self._target_ne = self.body.stopping_point(self.params.wpnav_accel)
        elif mode is RoverMode.RTL:
            self._target_ne = self.home_ne
        elif mode is RoverMode.AUTO and self.armed:
            self._auto_begin()

    def request_mode(self, base_mode: int, custom_mode: int, custom_sub_mode: int) -> MavResult:
        return self.request_mode_encoded(base_mode, custom_mode)

    def request_mode_encoded(self, base_mode: int, custom_mode: int) -> MavResult:
        """GCS_MAVLINK::_set_mode_common: only custom modes are understood."""
        if not base_mode & ModeFlag.CUSTOM_MODE_ENABLED:
            return MavResult.DENIED
        return self.set_mode(custom_mode)

    def nav_takeoff(self, altitude: float, frame: int) -> MavResult:
        return MavResult.UNSUPPORTED

    def nav_land(self) -> MavResult:
        return MavResult.UNSUPPORTED

    def return_to_launch(self) -> MavResult:
        return self.set_mode(RoverMode.RTL)

    def change_speed(self, kind: int, speed: float) -> MavResult:
        """GCS_MAVLINK_Rover: DO_CHANGE_SPEED; air speed counts as ground speed."""
        if kind in (_SPEED_TYPE_CLIMB, _SPEED_TYPE_DESCENT) or not 0 <= kind <= 3:
            return MavResult.DENIED
        if self.mode not in _SPEED_MODES or not (math.isfinite(speed) and speed > 0.0):
            return MavResult.FAILED
        self._speed = speed
        return MavResult.ACCEPTED

    def enter_guided(self) -> MavResult:
        return self.set_mode(RoverMode.GUIDED)

    def guided_goto(self, lat: float, lon: float, relative_alt: float) -> MavResult:
        """ModeGuided::set_desired_location; the altitude means nothing on the ground."""
        if self.mode is not RoverMode.GUIDED:
            return MavResult.FAILED
        if not (-90.0 <= lat <= 90.0 and -180.0 <= lon <= 180.0):
            return MavResult.DENIED
        self._target_ne = self.ne_of(lat, lon)
        return MavResult.ACCEPTED

    def guided_hold(self) -> None:
        if self.mode is RoverMode.GUIDED:
            self._target_ne = self.body.stopping_point(self.params.wpnav_accel)

    # -- missions --------------------------------------------------------------

    def _do_command(self, item: MissionItem) -> None:
        if item.command != MavCmd.DO_CHANGE_SPEED:
            super()._do_command(item)
        elif self.change_speed(int(item.param1), item.param2) is MavResult.ACCEPTED:
            self._say(Severity.INFO, f"speed: {item.param2:.1f} m/s")  # do_change_speed

    def _start_nav(self, item: MissionItem) -> None:
        """ModeAuto::start_command for the navigation commands a rover drives."""
        self._auto_item = item
        self._auto_hold_s = 0.0
        match item.command:
            case MavCmd.NAV_WAYPOINT | MavCmd.NAV_LOITER_TIME:
                self._target_ne = self._item_ne(item)
                self._auto_phase = AutoPhase.FLY
            case MavCmd.NAV_RETURN_TO_LAUNCH:
                self._target_ne = self.home_ne
                self._auto_phase = AutoPhase.RTL
            case _:
                # not a Rover command: verify_command skips it and the mission goes on
                self._say(Severity.WARNING, f"Skipping invalid cmd #{item.command}")
                self._auto_phase = AutoPhase.HOLD  # completes on the next step

    def _auto_complete(self) -> None:
        """ModeAuto::exit_mission with MIS_DONE_BEHAVE 0: stop, still in AUTO."""
        self._auto_item = None
        self._auto_phase = AutoPhase.DONE
        self._target_ne = None
        self._say(Severity.NOTICE, "Mission Complete")

    def _auto_step(self) -> None:
        """ModeAuto::update: drive the current command and verify it."""
        item = self._auto_item
        phase = self._auto_phase
        if phase in (AutoPhase.FLY, AutoPhase.RTL) and self._reached():
            if phase is AutoPhase.RTL:
                self._nav_done()
                return
            assert item is not None
            self._say(Severity.INFO, f"Reached waypoint #{item.seq}")
            self._auto_phase = AutoPhase.HOLD
            self._auto_hold_s = max(0.0, item.param1)
            self._target_ne = None  # loitering on the spot: stopped
        elif phase is AutoPhase.HOLD:
            self._auto_hold_s -= DT
            if self._auto_hold_s <= 1e-9:
                self._nav_done()

    def _reached(self) -> bool:
        if self._target_ne is None:
            return True
        here = (self.body.north, self.body.east)
        return math.dist(here, self._target_ne) <= self.params.wpnav_radius

    # -- stepping ----------------------------------------------------------

    def _step(self) -> None:
        p = self.params
        setpoint = self._control()
        self.body.step(setpoint, DT, p)
        moving = self.armed and self.body.groundspeed > 0.1
        amps = current_draw(self.armed, moving, self.body.throttle, 1.0)
        self.battery.step(DT, amps, p.sim_batt_drain)
        self._check_battery()
        self._step_sensors()

    def _control(self) -> Setpoint | None:
        if not self.armed:
            return None
        if self.mode is RoverMode.AUTO:
            if self._auto_phase is AutoPhase.IDLE and self.mission_count > 0:
                self._auto_begin()
            self._auto_step()
        elif self.mode is RoverMode.RTL and self._target_ne is not None and self._reached():
            self._say(Severity.INFO, "Reached destination")  # ModeRTL::update
            self._target_ne = None
        return Setpoint(
            self._target_ne,
            0.0,
            speed_xy=self._speed,
            speed_up=0.0,
            speed_down=0.0,
            on_wheels=True,
        )

    def _check_battery(self) -> None:
        """Rover::handle_battery_failsafe: BATT_FS_LOW_ACT 1 RTL, 2 HOLD."""
        if not self._battery_low():
            return
        action = self.params.batt_fs_low_act
        if action == 1 and self.set_mode(RoverMode.RTL) is MavResult.ACCEPTED:
            return
        if action in (1, 2):
            self.set_mode(RoverMode.HOLD)
