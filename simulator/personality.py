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
)
from simulator.param_table import ParamTable
from simulator.params import CopterParams
from simulator.px4_params import Px4ParamTable

# PX4's MIS_TAKEOFF_ALT: how high a take-off without an altitude climbs.
PX4_TAKEOFF_ALT_M = 2.5

# ArduCopter reports MAV_MODE_FLAG_GUIDED_ENABLED in these (GCS_MAVLINK_Copter::base_mode).
_ARDUCOPTER_GUIDED_FLAG = frozenset(
    {CopterMode.AUTO, CopterMode.GUIDED, CopterMode.LOITER, CopterMode.RTL, CopterMode.BRAKE}
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


class ArduCopterPersonality(Personality):
    autopilot = MavAutopilot.ARDUPILOTMEGA
    param_bytewise = False
    declined = MavResult.FAILED
    reboot_declined = MavResult.FAILED
    takeoff_alt_is_amsl = False
    mission_wire_offset = 0
    camera_feedback = True
    camera_index_from = 1

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

    def position_frame_ok(self, frame: int) -> bool:
        """MavlinkReceiver::handle_message_command_int: a position command is taken in
        MAV_FRAME_GLOBAL_INT (above mean sea level) only; any other frame is answered
        with MAV_RESULT_COMMAND_UNSUPPORTED_MAV_FRAME."""
        return frame == MavFrame.GLOBAL_INT


def personality_for(autopilot: str) -> Personality:
    if autopilot == "px4":
        return Px4Personality()
    return ArduCopterPersonality()
