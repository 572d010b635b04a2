"""The simulated multirotor as PX4 shows itself on the wire (see the package's docstring)."""

from __future__ import annotations

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
from simulator.params.px4 import GENERAL_METADATA_URI, Px4ParamTable, metadata_files
from simulator.params.table import ParamTable
from simulator.params.values import CopterParams
from simulator.personality.available_modes import PX4_AVAILABLE_MODES
from simulator.personality.base import Declined, ModeRequest, Personality

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
