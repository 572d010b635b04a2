"""A multirotor's state and what it is on the wire, and the calls its jobs make on
one another (arming, modes, guided flight, missions, return and landing, failsafes)."""

from __future__ import annotations

from abc import abstractmethod
from enum import Enum

from common.geodesy import GeoPoint
from simulator.mavconst import CopterMode, LandedState, MavResult, MavState, MavType
from simulator.params.table import ParamTable
from simulator.params.values import CopterParams
from simulator.personality.ardupilot import ArduCopterPersonality
from simulator.personality.base import Personality
from simulator.vehicle import AutoPhase, Vehicle
from simulator.vehicle.physics import Setpoint

BRAKE_DECEL = 7.5  # BRAKE_MODE_DECEL_RATE, m/s/s
BRAKE_SPEED_Z = 2.5  # BRAKE_MODE_SPEED_Z, m/s

# Modes that need a position estimate (Mode::requires_GPS) ...
POSITION_MODES = frozenset(
    {CopterMode.GUIDED, CopterMode.LOITER, CopterMode.RTL, CopterMode.AUTO, CopterMode.BRAKE}
)


class RtlStage(Enum):
    CLIMB = "climb"
    RETURN = "return"
    LOITER = "loiter"
    LAND = "land"


class CopterState(Vehicle):
    """One multirotor's state; each job's module adds what it does with it."""

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
        # GUIDED's velocity target (north, east, up m/s) and when it came; None: position only
        self._guided_vel: tuple[float, float, float] | None = None
        self._guided_vel_at = 0.0
        self._guided_yaw: float | None = None  # radians, a target's yaw to turn to
        self._taking_off = False
        self._land_ne = (0.0, 0.0)
        self._rtl_stage = RtlStage.CLIMB
        self._rtl_origin_ne = (0.0, 0.0)
        self._rtl_alt = 0.0
        self._rtl_loiter_s = 0.0
        self._armed_at = 0.0
        self._on_ground_s = 0.0
        self._disarm_timer_s = 0.0

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

    def takes_manual_control(self, sender: int) -> bool:
        return self.personality.takes_manual_control(sender, self.params, self.param_table)

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
        return self.position_ok or self.mode not in POSITION_MODES

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

    @property
    def upload_keeps_current_item(self) -> bool:
        return self.personality.upload_keeps_current_item

    def _landing(self) -> bool:
        """In the descent of LAND, of RTL, or of a mission's NAV_LAND / RTL."""
        rtl_landing = self._rtl_stage is RtlStage.LAND
        if self.mode is CopterMode.AUTO:
            return self._auto_phase is AutoPhase.LAND or (
                self._auto_phase is AutoPhase.RTL and rtl_landing
            )
        return self.mode is CopterMode.LAND or (self.mode is CopterMode.RTL and rtl_landing)

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

    def _stopping_alt(self, accel: float | None = None) -> float:
        climb = self.body.climb_rate
        decel = accel if accel is not None else self.params.wpnav_accel_z
        return self.body.alt + climb * abs(climb) / (2.0 * decel)

    # -- what one job asks of another --------------------------------------

    @abstractmethod
    def _disarm(self) -> None:
        """Disarm now, whatever the state (arming.py)."""

    @abstractmethod
    def _enter_mode(self, mode: CopterMode) -> None:
        """Switch mode without the checks (modes.py)."""

    @abstractmethod
    def _guided_hold(self) -> None:
        """Hold at the stopping point with GUIDED's speeds (guided.py)."""

    @abstractmethod
    def _autopilot_takeoff(self, above_home: float) -> MavResult:
        """PX4's Takeoff mode (guided.py)."""

    @abstractmethod
    def _mission_starts_with_takeoff(self) -> bool:
        """Whether the mission's first nav command is a take-off (auto.py)."""

    @abstractmethod
    def _start_rtl(self, stop_ne: tuple[float, float]) -> None:
        """Plan a return to launch from ``stop_ne`` (landing.py)."""

    @abstractmethod
    def _rtl_setpoint(self) -> Setpoint:
        """This step's setpoint of a return to launch (landing.py)."""

    @abstractmethod
    def _landing_setpoint(self, target_ne: tuple[float, float]) -> Setpoint:
        """This step's setpoint of a landing at ``target_ne`` (landing.py)."""
