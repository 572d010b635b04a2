"""MAV_RESULT names as the current MAVLink standard (common.xml) defines them.

The pymavlink dialect the agent loads lags the standard: it has no CANCELLED (6) and
names 9 "MAV_RESULT_ENUM_END", its end marker, so PX4's "unsupported frame" answer
read as the end of the enum. The names live here, from the standard itself, and a
code newer than this table is shown by its number, never as a neighbour's name.
"""

from __future__ import annotations

# common.xml, enum MAV_RESULT (https://mavlink.io/en/messages/common.html#MAV_RESULT)
MAV_RESULT_NAMES: dict[int, str] = {
    0: "MAV_RESULT_ACCEPTED",
    1: "MAV_RESULT_TEMPORARILY_REJECTED",
    2: "MAV_RESULT_DENIED",
    3: "MAV_RESULT_UNSUPPORTED",
    4: "MAV_RESULT_FAILED",
    5: "MAV_RESULT_IN_PROGRESS",
    6: "MAV_RESULT_CANCELLED",
    7: "MAV_RESULT_COMMAND_LONG_ONLY",
    8: "MAV_RESULT_COMMAND_INT_ONLY",
    9: "MAV_RESULT_COMMAND_UNSUPPORTED_MAV_FRAME",
    10: "MAV_RESULT_NOT_IN_CONTROL",
}
MAV_RESULT_COMMAND_UNSUPPORTED_MAV_FRAME = 9


def result_name(result: int) -> str:
    """The standard's name for ``result``, or ``MAV_RESULT <number>`` for one it lacks."""
    return MAV_RESULT_NAMES.get(int(result), f"MAV_RESULT {int(result)}")
