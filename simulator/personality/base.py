"""What every personality answers: a mode change decoded from the wire, or declined."""

from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass

from simulator.mavconst import (
    CopterMode,
    MavAutopilot,
    MavResult,
    MavState,
)
from simulator.params.table import ParamTable
from simulator.params.values import CopterParams
from simulator.personality.available_modes import AvailableMode

Sticks = tuple[int, int, int, int]  # MANUAL_CONTROL's x, y, z, r

# ArduPilot SITL's RC input: roll, pitch and yaw at mid stick, the throttle at its minimum.
TRANSMITTER_STICKS: Sticks = (0, 0, 0, 0)

# PX4's MIS_TAKEOFF_ALT: how high a take-off without an altitude climbs.
PX4_TAKEOFF_ALT_M = 2.5


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
