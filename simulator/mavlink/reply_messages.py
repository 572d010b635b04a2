"""The simulated autopilot's replies: to TIMESYNC, parameter, mission and mode requests,
commands, and its status texts."""

from __future__ import annotations

from typing import Any

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from protocol.mavlink_extra import (
    MAVLink_available_modes_message,
    MAVLink_component_metadata_message,
    MAVLink_current_mode_message,
)
from simulator.mavlink.message_context import MavMessage, MessageContext
from simulator.params.table import PARAM_ID_LEN
from simulator.params.wire import ParamValueBytes, value_bytes
from simulator.vehicle import StatusText
from simulator.vehicle.stored_mission import MissionItem

PARAM_INDEX_NONE = 65535  # PARAM_VALUE.param_index of the echo of a PARAM_SET (-1)


class ReplyMessages(MessageContext):
    """Answers to what a ground station asks, built from the vehicle's state."""

    def timesync(self, ts1: int) -> MavMessage:
        """The answer to a TIMESYNC request: nanoseconds since boot, the clock of
        time_boot_ms (ArduPilot: AP_HAL::micros64() * 1000)."""
        return mavlink2.MAVLink_timesync_message(int(self.copter.time_s * 1e6) * 1000, ts1)

    def available_modes(self, index: int) -> list[MavMessage] | None:
        """AVAILABLE_MODES for MAV_CMD_REQUEST_MESSAGE: every mode for ``index`` 0 (the
        first alone where the autopilot sends one per request, ArduPilot), else the one at
        ``index`` (1..N); None where the autopilot does not list its modes (the rover) or
        there is no such index."""
        personality = getattr(self.copter, "personality", None)
        modes = personality.available_modes if personality is not None else ()
        total = len(modes)
        if personality is None or not modes or not 0 <= index <= total:
            return None
        every = range(1, total + 1) if personality.lists_every_mode_at_once else (1,)
        indices = every if index == 0 else (index,)
        return [
            MAVLink_available_modes_message(
                total,
                at,
                modes[at - 1].standard_mode,
                modes[at - 1].custom_mode,
                modes[at - 1].properties,
                modes[at - 1].name.encode(),
            )
            for at in indices
        ]

    def component_metadata(self, uri: str) -> MavMessage:
        """COMPONENT_METADATA: where the general metadata file is (an mftp:// address)."""
        return MAVLink_component_metadata_message(self._time_boot_ms, 0, uri.encode())

    def current_mode(self) -> MavMessage:
        """CURRENT_MODE (PX4 sends it on each change): the mode now, and as intended."""
        custom_mode = self.copter.custom_mode()
        personality = getattr(self.copter, "personality", None)
        listed = personality.available_modes if personality is not None else ()
        standard = next(
            (mode.standard_mode for mode in listed if mode.custom_mode == custom_mode), 0
        )
        return MAVLink_current_mode_message(standard, custom_mode, custom_mode)

    def param_value(self, name: str, index: int | None = None) -> MavMessage:
        """PARAM_VALUE of a stored parameter; ``index`` None for the echo of a PARAM_SET."""
        table = self.copter.param_table
        value = table.get(name)
        assert value is not None, name
        param_type = table.definition(name).type
        return ParamValueBytes(
            name.encode("ascii")[:PARAM_ID_LEN],
            value_bytes(value, param_type, self.copter.param_bytewise),
            int(param_type),
            table.count,
            PARAM_INDEX_NONE if index is None else index,
        )

    @staticmethod
    def mission_item_int(item: MissionItem, target_system: int, target_component: int) -> Any:
        return mavlink2.MAVLink_mission_item_int_message(
            target_system,
            target_component,
            item.seq,
            item.frame,
            item.command,
            0,
            item.autocontinue,
            item.param1,
            item.param2,
            item.param3,
            item.param4,
            item.x,
            item.y,
            item.z,
            0,
        )

    @staticmethod
    def mission_count(count: int, target_system: int, target_component: int) -> MavMessage:
        return mavlink2.MAVLink_mission_count_message(target_system, target_component, count, 0)

    @staticmethod
    def mission_request_int(seq: int, target_system: int, target_component: int) -> MavMessage:
        return mavlink2.MAVLink_mission_request_int_message(target_system, target_component, seq, 0)

    @staticmethod
    def mission_ack(result: int, target_system: int, target_component: int) -> MavMessage:
        return mavlink2.MAVLink_mission_ack_message(target_system, target_component, result, 0)

    @staticmethod
    def mission_item_reached(seq: int) -> MavMessage:
        return mavlink2.MAVLink_mission_item_reached_message(seq)

    @staticmethod
    def statustext_of(severity: int, text: str) -> MavMessage:
        return mavlink2.MAVLink_statustext_message(
            int(severity), text.encode("ascii", errors="replace")[:50]
        )

    @staticmethod
    def statustext(status: StatusText) -> MavMessage:
        text = status.text.encode("ascii", errors="replace")[:50]
        return mavlink2.MAVLink_statustext_message(int(status.severity), text)

    @staticmethod
    def command_ack(
        command: int, result: int, target_system: int, target_component: int
    ) -> MavMessage:
        return mavlink2.MAVLink_command_ack_message(
            command, int(result), 0, 0, target_system, target_component
        )

    @staticmethod
    def message_interval(msg_id: int, interval_us: int) -> MavMessage:
        return mavlink2.MAVLink_message_interval_message(msg_id, interval_us)
