"""A recorded flight, as an agent with its token leaves it in the store."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from vehicle_agents.tlog.recorder import TlogRecorder

# Tokens as an operator writes them into a compose file: no gcs_v_ prefix.
OPERATOR_TOKEN = "field-kit-alpha-0123456789abcdef"


def _packed(message: Any) -> Any:
    sender = mavlink2.MAVLink(None, srcSystem=1, srcComponent=1)
    (parsed,) = mavlink2.MAVLink(None).parse_buffer(message.pack(sender))
    return parsed


def _heartbeat(armed: bool) -> Any:
    mode = mavlink2.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED
    if armed:
        mode |= mavlink2.MAV_MODE_FLAG_SAFETY_ARMED
    return _packed(
        mavlink2.MAVLink_heartbeat_message(
            mavlink2.MAV_TYPE_QUADROTOR, mavlink2.MAV_AUTOPILOT_ARDUPILOTMEGA, mode, 4, 4, 3
        )
    )


def _recorded_flight(directory: Path, vehicle: str) -> TlogRecorder:
    """A recorder holding one finished flight, recorded from real MAVLink bytes."""
    recorder = TlogRecorder(directory, vehicle)
    recorder.record(_heartbeat(armed=True), 1_700_000_000.0)
    for index in range(20):
        position = mavlink2.MAVLink_global_position_int_message(
            index * 100, 473977420 + index, 85455940, 488000, 1000, 1, 2, 3, 9000
        )
        recorder.record(_packed(position), 1_700_000_000.1 + index / 10)
    recorder.record(_heartbeat(armed=False), 1_700_000_003.0)
    assert len(recorder.finished) == 1
    return recorder
