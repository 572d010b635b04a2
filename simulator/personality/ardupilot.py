"""The simulated multirotor as ArduCopter shows itself on the wire."""

from __future__ import annotations

from simulator.mavconst import (
    CopterMode,
    MavAutopilot,
    MavResult,
    MavState,
    ModeFlag,
)
from simulator.params.table import ParamTable
from simulator.params.values import CopterParams
from simulator.personality.available_modes import ARDUCOPTER_AVAILABLE_MODES
from simulator.personality.base import (
    TRANSMITTER_STICKS,
    Declined,
    ModeRequest,
    Personality,
    Sticks,
)

# ArduCopter reports MAV_MODE_FLAG_GUIDED_ENABLED in these (GCS_MAVLINK_Copter::base_mode).
_ARDUCOPTER_GUIDED_FLAG = frozenset(
    {CopterMode.AUTO, CopterMode.GUIDED, CopterMode.LOITER, CopterMode.RTL, CopterMode.BRAKE}
)


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
