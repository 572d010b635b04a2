"""Which autopilot the simulated multirotor plays: how it names its modes on the wire and
answers what it declines.

The flight behaviour is the copter's own (ArduCopter's rules, see `copter.py`); a
personality maps its flight modes to and from the autopilot's encoding, as a GCS sees it:

* ArduCopter: HEARTBEAT.custom_mode is the mode number; DO_SET_MODE param2 is that number;
  a declined command is MAV_RESULT_FAILED.
* PX4 (commander/px4_custom_mode.h, mavlink_messages.cpp, Commander.cpp): custom_mode
  packs main mode << 16 and sub mode << 24; DO_SET_MODE takes them apart in param2 and
  param3; a declined mode change, arming or disarming is TEMPORARILY_REJECTED and a
  reboot while armed DENIED; NAV_TAKEOFF's altitude is above mean sea level. Its modes
  land on the copter's behaviours: MANUAL, STABILIZED and ALTCTL hold altitude with the
  sticks centred (STABILIZE here), POSCTL and AUTO.LOITER ("Hold") hold position
  (LOITER), AUTO.MISSION flies the mission (AUTO), AUTO.RTL and AUTO.LAND are RTL and
  LAND, and a reposition is flown in Hold, as PX4's navigator does. Switched to Mission
  it does not arm itself (Commander arms on request only); armed in Mission on the
  ground with a mission it takes off on the take-off item, and a take-off item with a
  position is flown to once the climb is done. A reposition or a
  set-home sent as COMMAND_INT is taken only in MAV_FRAME_GLOBAL_INT (MAV_RESULT 9,
  COMMAND_UNSUPPORTED_MAV_FRAME, for any other frame). Its parameters have PX4's names
  and types, integers sent bytewise (`px4_params`, `param_wire`). Its camera tells of
  a shutter with CAMERA_IMAGE_CAPTURED, and with CAMERA_TRIGGER where a GCS asked for it,
  never with ArduPilot's CAMERA_FEEDBACK.

Manual control: ArduCopter flies MANUAL_CONTROL from SYSID_MYGCS only, as an RC override,
and without one its LOITER flies SITL's transmitter (throttle at its minimum: it sinks).
PX4 takes it from any sender when COM_RC_IN_MODE lets MAVLink input in, refuses POSCTL in
the air until some has come, and when it stops flies NAV_RCL_ACT after COM_RC_LOSS_T +
COM_FAIL_ACT_T unless COM_RCL_EXCEPT exempts the mode (bit 0 Mission, bit 1 Hold).
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass

from simulator.mavconst import (
    CopterMode,
    MavAutopilot,
    MavFrame,
    MavResult,
    MavState,
    ModeFlag,
    Px4AutoMode,
    Px4MainMode,
    Px4PosctlMode,
)
from simulator.param_table import ParamTable
from simulator.params import CopterParams
from simulator.px4_params import GENERAL_METADATA_URI, Px4ParamTable, metadata_files

Sticks = tuple[int, int, int, int]  # MANUAL_CONTROL's x, y, z, r
# ArduPilot SITL's RC input: roll, pitch and yaw at mid stick, the throttle at its minimum.
TRANSMITTER_STICKS: Sticks = (0, 0, 0, 0)

# PX4's MIS_TAKEOFF_ALT: how high a take-off without an altitude climbs.
PX4_TAKEOFF_ALT_M = 2.5

# ArduCopter reports MAV_MODE_FLAG_GUIDED_ENABLED in these (GCS_MAVLINK_Copter::base_mode).
_ARDUCOPTER_GUIDED_FLAG = frozenset(
    {CopterMode.AUTO, CopterMode.GUIDED, CopterMode.LOITER, CopterMode.RTL, CopterMode.BRAKE}
)


@dataclass(frozen=True)
class AvailableMode:
    """One entry of the autopilot's AVAILABLE_MODES list (MAVLink standard modes)."""

    custom_mode: int  # as HEARTBEAT carries it
    name: str  # empty for PX4's standard modes, which it names by standard_mode alone
    standard_mode: int = 0  # MAV_STANDARD_MODE; 0 NON_STANDARD
    properties: int = 0  # MAV_MODE_PROPERTY: 1 ADVANCED, 2 NOT_USER_SELECTABLE


ADVANCED = 1
NOT_USER_SELECTABLE = 2
# MAV_STANDARD_MODE values PX4 reports (mode_util::getStandardModeFromNavState)
STANDARD_POSITION_HOLD, STANDARD_ORBIT, STANDARD_ALTITUDE_HOLD = 1, 2, 4
STANDARD_SAFE_RECOVERY, STANDARD_MISSION, STANDARD_LAND, STANDARD_TAKEOFF = 5, 6, 7, 8


def _px4(main: int, sub: int = 0) -> int:
    return (main << 16) | (sub << 24)


# GCS_MAVLINK_Copter::send_available_mode of ArduCopter 4.7, for a standard build (no
# FLOWHOLD, FOLLOW, ZIGZAG, SYSTEMID, AUTOROTATE, TURTLE): its order, its mode numbers, its
# modes' own names, no properties, all NON_STANDARD. AUTO RTL comes first, as there.
ARDUCOPTER_AVAILABLE_MODES: tuple[AvailableMode, ...] = tuple(
    AvailableMode(int(mode), name)
    for mode, name in (
        (CopterMode.AUTO_RTL, "AUTO RTL"),
        (CopterMode.AUTO, "AUTO"),
        (CopterMode.ACRO, "ACRO"),
        (CopterMode.STABILIZE, "STABILIZE"),
        (CopterMode.ALT_HOLD, "ALT_HOLD"),
        (CopterMode.CIRCLE, "CIRCLE"),
        (CopterMode.LOITER, "LOITER"),
        (CopterMode.GUIDED, "GUIDED"),
        (CopterMode.LAND, "LAND"),
        (CopterMode.RTL, "RTL"),
        (CopterMode.DRIFT, "DRIFT"),
        (CopterMode.SPORT, "SPORT"),
        (CopterMode.FLIP, "FLIP"),
        (CopterMode.AUTOTUNE, "AUTOTUNE"),
        (CopterMode.POSHOLD, "POSHOLD"),
        (CopterMode.BRAKE, "BRAKE"),
        (CopterMode.THROW, "THROW"),
        (CopterMode.AVOID_ADSB, "AVOID_ADSB"),
        (CopterMode.GUIDED_NOGPS, "GUIDED_NOGPS"),
        (CopterMode.SMART_RTL, "SMARTRTL"),
    )
)

_M, _A = Px4MainMode, Px4AutoMode
PX4_EXTERNAL_MODES = 8  # NAVIGATION_STATE_EXTERNAL1..8
PX4_SUB_MODE_EXTERNAL1 = 11  # PX4_CUSTOM_SUB_MODE_EXTERNAL1, after VTOL_TAKEOFF (10)
# PX4's AVAILABLE_MODES stream for a multicopter (1.16): every valid nav state in nav
# state order (mode_util::getValidNavStates), custom_mode from get_px4_custom_mode, a name
# only for non-standard modes (mode_util::nav_state_names), ADVANCED for all but Altitude,
# Position and the external modes (mode_util::isAdvanced), and NOT_USER_SELECTABLE for
# Termination and for external modes no ROS 2 component registered ("(Mode not
# available)", ModeManagement::getModeStatus). No RATTITUDE, no RTGS: PX4 has neither.
PX4_AVAILABLE_MODES: tuple[AvailableMode, ...] = (
    AvailableMode(_px4(_M.MANUAL), "Manual", properties=ADVANCED),
    AvailableMode(_px4(_M.ALTCTL), "", STANDARD_ALTITUDE_HOLD),
    AvailableMode(_px4(_M.POSCTL), "", STANDARD_POSITION_HOLD),
    AvailableMode(_px4(_M.AUTO, _A.MISSION), "", STANDARD_MISSION, ADVANCED),
    AvailableMode(_px4(_M.AUTO, _A.LOITER), "Hold", properties=ADVANCED),
    AvailableMode(_px4(_M.AUTO, _A.RTL), "", STANDARD_SAFE_RECOVERY, ADVANCED),
    AvailableMode(_px4(_M.ACRO), "Acro", properties=ADVANCED),
    AvailableMode(_px4(_M.AUTO, _A.LAND), "Descend", properties=ADVANCED),
    AvailableMode(_px4(_M.MANUAL), "Termination", properties=ADVANCED | NOT_USER_SELECTABLE),
    AvailableMode(_px4(_M.OFFBOARD), "Offboard", properties=ADVANCED),
    AvailableMode(_px4(_M.STABILIZED), "Stabilized", properties=ADVANCED),
    AvailableMode(_px4(_M.AUTO, _A.TAKEOFF), "", STANDARD_TAKEOFF, ADVANCED),
    AvailableMode(_px4(_M.AUTO, _A.LAND), "", STANDARD_LAND, ADVANCED),
    AvailableMode(_px4(_M.AUTO, _A.FOLLOW_TARGET), "Follow Target", properties=ADVANCED),
    AvailableMode(_px4(_M.AUTO, _A.PRECLAND), "Precision Landing", properties=ADVANCED),
    AvailableMode(_px4(_M.POSCTL, Px4PosctlMode.ORBIT), "", STANDARD_ORBIT, ADVANCED),
    AvailableMode(_px4(_M.AUTO, _A.VTOL_TAKEOFF), "VTOL Takeoff", properties=ADVANCED),
    *(
        AvailableMode(
            _px4(_M.AUTO, PX4_SUB_MODE_EXTERNAL1 + index),
            "(Mode not available)",
            properties=NOT_USER_SELECTABLE,
        )
        for index in range(PX4_EXTERNAL_MODES)
    ),
)


@dataclass(frozen=True)
class ModeRequest:
    """A mode change decoded from the wire: the copter mode number that flies it, and
    what the autopilot will call it."""

    mode: int
    wire: tuple[int, int]  # (main, sub) for PX4; (number, 0) for ArduCopter
    takeoff: bool = False  # PX4's AUTO.TAKEOFF: climb to MIS_TAKEOFF_ALT, then Hold


@dataclass(frozen=True)
class Declined:
    """A mode change answered without trying it, and what the autopilot says about it."""

    result: MavResult
    text: str | None = None


class Personality(ABC):
    autopilot: MavAutopilot
    # PARAM_VALUE/PARAM_SET: integers copied bytewise into the float (PX4), or cast (ArduPilot)
    param_bytewise: bool
    declined: MavResult  # the answer to an arming, disarming or mode change it declines
    reboot_declined: MavResult  # the answer to a reboot while armed
    takeoff_alt_is_amsl: bool  # NAV_TAKEOFF param7: above mean sea level, or above home
    # Where the mission starts on the wire: ArduPilot keeps home as item 0, PX4 (as the
    # MAVLink spec has it) starts the mission itself at 0. The simulator always stores
    # home first; this is how far its numbers are from the wire's.
    mission_wire_offset: int
    # How the camera tells of a shutter: ArduPilot's AP_Camera sends CAMERA_FEEDBACK (its
    # img_idx from 1) to every link; PX4 sends CAMERA_IMAGE_CAPTURED (camera_feedback) to
    # every link and CAMERA_TRIGGER (camera_trigger; both numbered from 0) only to a link
    # that asked for it with SET_MESSAGE_INTERVAL (mavlink_main.cpp streams it to onboard
    # links alone).
    camera_feedback: bool
    camera_index_from: int
    # AVAILABLE_MODES, as the autopilot answers MAV_CMD_REQUEST_MESSAGE (PX4 from 1.15,
    # ArduPilot from 4.7), and whether it sends CURRENT_MODE on each mode change (PX4's
    # CURRENT_MODE stream).
    available_modes: tuple[AvailableMode, ...] = ()
    # Whether a request for every mode (param2 0) brings them all. ArduPilot's does not:
    # GCS_MAVLINK::send_available_modes sends one mode each time the deferred message
    # goes out, and only its PARAMS stream (SRn_PARAMS) sends it again, so a GCS that
    # sets its rates with SET_MESSAGE_INTERVAL gets mode 1 alone (ArduCopter 4.7 SITL,
    # three requests); each mode asked for by its index comes (param2 N).
    lists_every_mode_at_once: bool = True
    # Whether a mission upload keeps the current item's index: PX4's does unless an item
    # comes flagged current; ArduPilot starts a new mission from its first item.
    upload_keeps_current_item: bool = False
    sends_current_mode: bool = False
    # The component metadata PX4 publishes (COMPONENT_METADATA's mftp:// address, and the
    # files its MAVLink FTP serves); ArduPilot publishes none.
    general_metadata_uri: str | None = None

    def metadata_files(self) -> dict[str, bytes]:
        return {}

    # A mission's NAV_TAKEOFF with a position: PX4 climbs, then flies there as to a
    # waypoint (navigator/mission.cpp: "if we just did a normal takeoff navigate to the
    # actual waypoint now"); ArduCopter climbs where it is and ignores it.
    takeoff_flies_to_position: bool = False

    @abstractmethod
    def base_mode(self, mode: CopterMode, armed: bool) -> int: ...

    @abstractmethod
    def system_status(self, armed: bool, landed: bool, failsafe: bool) -> MavState: ...

    @abstractmethod
    def custom_mode(self, mode: CopterMode, taking_off: bool) -> int: ...

    @abstractmethod
    def decode(
        self, base_mode: int, custom_mode: int, custom_sub_mode: int
    ) -> ModeRequest | Declined:
        """A DO_SET_MODE request."""

    @abstractmethod
    def decode_encoded(self, base_mode: int, custom_mode: int) -> ModeRequest | Declined:
        """A SET_MODE request, whose custom_mode is encoded as HEARTBEAT's."""

    def selected(self, request: ModeRequest) -> None:
        """A decoded request was accepted."""
        return  # nothing to do by default

    def takeoff_selected(self) -> None:
        """A take-off command was accepted."""
        return  # nothing to do by default

    def allows_arming(self, mode: CopterMode) -> bool:
        return True

    def disarm_declined_text(self) -> str | None:
        """What the autopilot says when it refuses a plain disarm in the air."""
        return None

    def new_param_table(self, params: CopterParams, system_id: int) -> ParamTable:
        """The parameters under the autopilot's names."""
        return ParamTable(params, system_id)

    def position_frame_ok(self, frame: int) -> bool:
        """Whether a COMMAND_INT reposition or set-home in ``frame`` is taken."""
        return True

    @abstractmethod
    def takes_manual_control(self, sender: int, params: CopterParams, table: ParamTable) -> bool:
        """Whether a MANUAL_CONTROL from system ``sender`` is flown."""

    def transmitter_sticks(self) -> Sticks | None:
        """What a pilot mode flies with no fresh MANUAL_CONTROL; None: it holds."""
        return None

    def sticks_fly(self, mode: CopterMode) -> bool:
        """Whether the copter's LOITER flies the sticks in the mode it reports now."""
        return True

    def needs_manual_input(self, request: ModeRequest, table: ParamTable) -> bool:
        """Whether the mode asked for needs manual input the autopilot must have had."""
        return False

    def manual_loss_action(
        self, mode: CopterMode, silent_s: float, table: ParamTable
    ) -> CopterMode | None:
        """The mode a manual-control-loss failsafe switches to, manual input having
        been silent for ``silent_s``; None: no failsafe (yet)."""
        return None


class ArduCopterPersonality(Personality):
    autopilot = MavAutopilot.ARDUPILOTMEGA
    param_bytewise = False
    declined = MavResult.FAILED
    reboot_declined = MavResult.FAILED
    takeoff_alt_is_amsl = False
    mission_wire_offset = 0
    camera_feedback = True
    camera_index_from = 1
    available_modes = ARDUCOPTER_AVAILABLE_MODES
    lists_every_mode_at_once = False

    def base_mode(self, mode: CopterMode, armed: bool) -> int:
        """GCS_MAVLINK_Copter::base_mode."""
        flags = (
            ModeFlag.CUSTOM_MODE_ENABLED
            | ModeFlag.STABILIZE_ENABLED
            | ModeFlag.MANUAL_INPUT_ENABLED
        )
        if mode in _ARDUCOPTER_GUIDED_FLAG:
            flags |= ModeFlag.GUIDED_ENABLED
        if armed:
            flags |= ModeFlag.SAFETY_ARMED
        return int(flags)

    def custom_mode(self, mode: CopterMode, taking_off: bool) -> int:
        return int(mode)

    def system_status(self, armed: bool, landed: bool, failsafe: bool) -> MavState:
        """CRITICAL in a failsafe, else STANDBY while landed (armed or not), ACTIVE in the
        air (GCS_MAVLINK_Copter::vehicle_system_status)."""
        if failsafe:
            return MavState.CRITICAL
        return MavState.STANDBY if landed else MavState.ACTIVE

    def decode(
        self, base_mode: int, custom_mode: int, custom_sub_mode: int
    ) -> ModeRequest | Declined:
        """GCS_MAVLINK::_set_mode_common: only custom modes are understood."""
        return self.decode_encoded(base_mode, custom_mode)

    def decode_encoded(self, base_mode: int, custom_mode: int) -> ModeRequest | Declined:
        if not base_mode & ModeFlag.CUSTOM_MODE_ENABLED:
            return Declined(MavResult.DENIED)
        return ModeRequest(custom_mode, (custom_mode, 0))

    def takes_manual_control(self, sender: int, params: CopterParams, table: ParamTable) -> bool:
        # GCS_MAVLINK::handle_manual_control: only from SYSID_MYGCS, else ignored
        return sender == params.sysid_mygcs

    def transmitter_sticks(self) -> Sticks | None:
        """RC input with no override: SITL's transmitter has its sticks centred and the
        throttle at its minimum (RC3 1000 us), so LOITER descends at PILOT_SPEED_DN."""
        return TRANSMITTER_STICKS

    def allows_arming(self, mode: CopterMode) -> bool:
        # Mode::allows_arming is false in RTL, LAND, AUTO and BRAKE
        return mode not in (CopterMode.RTL, CopterMode.LAND, CopterMode.AUTO, CopterMode.BRAKE)


_PX4_MODES: dict[tuple[int, int], int] = {
    (Px4MainMode.MANUAL, 0): CopterMode.STABILIZE,
    (Px4MainMode.STABILIZED, 0): CopterMode.STABILIZE,
    (Px4MainMode.ALTCTL, 0): CopterMode.STABILIZE,
    (Px4MainMode.POSCTL, 0): CopterMode.LOITER,
    (Px4MainMode.AUTO, Px4AutoMode.LOITER): CopterMode.LOITER,
    (Px4MainMode.AUTO, Px4AutoMode.MISSION): CopterMode.AUTO,
    (Px4MainMode.AUTO, Px4AutoMode.RTL): CopterMode.RTL,
    (Px4MainMode.AUTO, Px4AutoMode.LAND): CopterMode.LAND,
    (Px4MainMode.AUTO, Px4AutoMode.TAKEOFF): CopterMode.GUIDED,
}
# What PX4 reports for a copter mode it was not asked for by name (a failsafe's RTL or
# LAND, a reposition's guided flight, the mode at boot).
_PX4_REPORTED: dict[CopterMode, tuple[int, int]] = {
    CopterMode.STABILIZE: (Px4MainMode.MANUAL, 0),
    CopterMode.LOITER: (Px4MainMode.AUTO, Px4AutoMode.LOITER),
    CopterMode.BRAKE: (Px4MainMode.AUTO, Px4AutoMode.LOITER),
    CopterMode.GUIDED: (Px4MainMode.AUTO, Px4AutoMode.LOITER),
    CopterMode.AUTO: (Px4MainMode.AUTO, Px4AutoMode.MISSION),
    CopterMode.RTL: (Px4MainMode.AUTO, Px4AutoMode.RTL),
    CopterMode.LAND: (Px4MainMode.AUTO, Px4AutoMode.LAND),
}
# COM_RC_IN_MODE values that take MAVLink manual input: 1 MAVLink only, 2 and 3 RC too
_PX4_MAVLINK_INPUT = (1, 2, 3)
# NAV_RCL_ACT: what the manual-control-loss failsafe flies
_PX4_RCL_ACTIONS = {1: CopterMode.LOITER, 2: CopterMode.RTL, 3: CopterMode.LAND}
_TAKEOFF = (int(Px4MainMode.AUTO), int(Px4AutoMode.TAKEOFF))
_HOLD = (int(Px4MainMode.AUTO), int(Px4AutoMode.LOITER))
_AUTO_FLAGS = ModeFlag.AUTO_ENABLED | ModeFlag.STABILIZE_ENABLED | ModeFlag.GUIDED_ENABLED


class Px4Personality(Personality):
    autopilot = MavAutopilot.PX4
    param_bytewise = True
    declined = MavResult.TEMPORARILY_REJECTED
    reboot_declined = MavResult.DENIED
    takeoff_alt_is_amsl = True
    mission_wire_offset = 1
    camera_feedback = False
    camera_index_from = 0
    takeoff_flies_to_position = True
    available_modes = PX4_AVAILABLE_MODES
    upload_keeps_current_item = True
    sends_current_mode = True
    general_metadata_uri = GENERAL_METADATA_URI

    def metadata_files(self) -> dict[str, bytes]:
        return metadata_files()

    def __init__(self) -> None:
        # the PX4 mode last selected by name, and the copter mode that flies it
        self._selected: ModeRequest | None = None

    def _wire(self, mode: CopterMode, taking_off: bool) -> tuple[int, int]:
        selected = self._selected
        if selected is None or selected.mode != mode:
            return _PX4_REPORTED.get(mode, (Px4MainMode.MANUAL, 0))
        if selected.wire == _TAKEOFF and not taking_off:
            return _HOLD  # AUTO.TAKEOFF hands over to Hold at the take-off altitude
        return selected.wire

    def base_mode(self, mode: CopterMode, armed: bool) -> int:
        """get_mavlink_navigation_mode, for a rotary wing."""
        main, _ = self._wire(mode, taking_off=False)
        flags = ModeFlag.CUSTOM_MODE_ENABLED
        if armed:
            flags |= ModeFlag.SAFETY_ARMED
        if main in (Px4MainMode.AUTO, Px4MainMode.OFFBOARD):
            flags |= _AUTO_FLAGS
        elif main == Px4MainMode.POSCTL:
            flags |= (
                ModeFlag.MANUAL_INPUT_ENABLED | ModeFlag.STABILIZE_ENABLED | ModeFlag.GUIDED_ENABLED
            )
        else:
            flags |= ModeFlag.MANUAL_INPUT_ENABLED | ModeFlag.STABILIZE_ENABLED
        return int(flags)

    def custom_mode(self, mode: CopterMode, taking_off: bool) -> int:
        main, sub = self._wire(mode, taking_off)
        return (main << 16) | (sub << 24)

    def system_status(self, armed: bool, landed: bool, failsafe: bool) -> MavState:
        """get_mavlink_mode_state: from the arming state alone."""
        return MavState.ACTIVE if armed else MavState.STANDBY

    def decode(
        self, base_mode: int, custom_mode: int, custom_sub_mode: int
    ) -> ModeRequest | Declined:
        """Commander's VEHICLE_CMD_DO_SET_MODE (custom modes; the legacy base-mode-only
        requests are not simulated)."""
        if not base_mode & ModeFlag.CUSTOM_MODE_ENABLED:
            return Declined(MavResult.DENIED)
        main, sub = custom_mode & 0xFF, custom_sub_mode & 0xFF
        if main == Px4MainMode.OFFBOARD:
            # Commander takes the request, but without an offboard setpoint stream the
            # vehicle stays in the mode it was in (seen on PX4 SITL: ACCEPTED, still Hold).
            return Declined(MavResult.ACCEPTED)
        if main == Px4MainMode.POSCTL and sub == Px4PosctlMode.ORBIT:
            return Declined(self.declined, "ORBIT mode not simulated")
        if main == Px4MainMode.AUTO:
            if sub == 0:
                sub = Px4AutoMode.MISSION  # AUTO without a sub mode is a mission
            elif sub not in Px4AutoMode.__members__.values():
                return Declined(self.declined, "Unsupported auto mode")
        else:
            sub = 0
        mode = _PX4_MODES.get((main, sub))
        if mode is not None:
            return ModeRequest(mode, (main, sub), takeoff=(main, sub) == _TAKEOFF)
        if main in Px4MainMode.__members__.values():
            name = Px4MainMode(main).name if main != Px4MainMode.AUTO else Px4AutoMode(sub).name
            return Declined(self.declined, f"{name} mode not simulated")
        # an unknown main mode changes nothing, and Commander still accepts it
        return Declined(MavResult.ACCEPTED)

    def decode_encoded(self, base_mode: int, custom_mode: int) -> ModeRequest | Declined:
        return self.decode(base_mode, (custom_mode >> 16) & 0xFF, (custom_mode >> 24) & 0xFF)

    def selected(self, request: ModeRequest) -> None:
        self._selected = request

    def takeoff_selected(self) -> None:
        self._selected = ModeRequest(CopterMode.GUIDED, _TAKEOFF)

    def allows_arming(self, mode: CopterMode) -> bool:
        # PX4 arms in Mission (the mission then takes off), not in Return or Land
        return mode not in (CopterMode.RTL, CopterMode.LAND)

    def disarm_declined_text(self) -> str | None:
        return "Disarming denied: not landed"

    def new_param_table(self, params: CopterParams, system_id: int) -> ParamTable:
        return Px4ParamTable(params, system_id)

    def takes_manual_control(self, sender: int, params: CopterParams, table: ParamTable) -> bool:
        """MavlinkReceiver::handle_message_manual_control checks only the target; the
        manual control selector takes MAVLink input if COM_RC_IN_MODE lets it in."""
        return round(table.get("COM_RC_IN_MODE") or 0) in _PX4_MAVLINK_INPUT

    def sticks_fly(self, mode: CopterMode) -> bool:
        # Hold (AUTO.LOITER) flies no sticks; POSCTL does
        return self._wire(mode, taking_off=False)[0] == Px4MainMode.POSCTL

    def needs_manual_input(self, request: ModeRequest, table: ParamTable) -> bool:
        """Position mode (mode_util's mode_req_manual_control) is refused in the air until
        manual input has come: TEMPORARILY_REJECTED."""
        return request.wire[0] == Px4MainMode.POSCTL

    def manual_loss_action(
        self, mode: CopterMode, silent_s: float, table: ParamTable
    ) -> CopterMode | None:
        """The manual-control-loss failsafe: input silent for COM_RC_LOSS_T is lost, and
        COM_FAIL_ACT_T later NAV_RCL_ACT's mode is flown (1 Hold, 2 Return, 3 Land; the
        Hold delay is left out), unless COM_RCL_EXCEPT exempts the mode now flown."""
        lost_after = (table.get("COM_RC_LOSS_T") or 0.0) + (table.get("COM_FAIL_ACT_T") or 0.0)
        if silent_s <= lost_after or mode in (CopterMode.RTL, CopterMode.LAND):
            return None
        exempt = round(table.get("COM_RCL_EXCEPT") or 0)
        wire = self._wire(mode, taking_off=False)
        if (exempt & 1 and mode is CopterMode.AUTO) or (exempt & 2 and wire == _HOLD):
            return None
        return _PX4_RCL_ACTIONS.get(round(table.get("NAV_RCL_ACT") or 0))

    def position_frame_ok(self, frame: int) -> bool:
        """MavlinkReceiver::handle_message_command_int: a position command is taken in
        MAV_FRAME_GLOBAL_INT (above mean sea level) only; any other frame is answered
        with MAV_RESULT_COMMAND_UNSUPPORTED_MAV_FRAME."""
        return frame == MavFrame.GLOBAL_INT


def personality_for(autopilot: str) -> Personality:
    if autopilot == "px4":
        return Px4Personality()
    return ArduCopterPersonality()
