"""Per-connection telemetry schedule, in sim seconds, and the requests that change it.

Rates are per sim second, as ArduPilot SITL's with SIM_SPEEDUP: at a speed-up of N a
10 Hz stream sends 10 N messages a wall second, and a client that times the stream by
the messages' own time_boot_ms finds 10 Hz at any speed-up. What each message says is
the sim state at the moment it is sent. Clients set rates per message with
SET_MESSAGE_INTERVAL (handled in ``commands``) or per group with REQUEST_DATA_STREAM.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from enum import IntEnum
from typing import Any

from simulator.config import MessageIntervalSupport
from simulator.mavconst import MavCmd, MavResult, MsgId
from simulator.mavlink.commands import MessageHandler, Reply
from simulator.mavlink.telemetry import GPS2_RAW

MIN_INTERVAL_S = 0.01  # 100 Hz at most per message
# A message late by less than this (a tick held up a moment, which at a speed-up is that
# many times longer in sim time) keeps its rhythm: it is sent at the next ticks until it
# has caught up. Later than that (a stall, a reboot's silence), it resumes from now
# rather than sending a burst.
CATCH_UP_S = 1.0


class StreamSchedule:
    """When each message id is next due on one connection."""

    def __init__(self, default_rates_hz: Mapping[int, float], now: float) -> None:
        self._defaults = {
            msg_id: 1.0 / rate for msg_id, rate in default_rates_hz.items() if rate > 0.0
        }
        self._intervals = dict(self._defaults)
        # everything is due at once on connect, so a new client learns the state quickly
        self._next_due = dict.fromkeys(self._intervals, now)

    def interval(self, msg_id: int) -> float | None:
        """Seconds between sends, or None if the message is not streamed."""
        return self._intervals.get(msg_id)

    def set_interval(self, msg_id: int, interval_s: float | None, now: float) -> None:
        """Stream ``msg_id`` every ``interval_s`` seconds; None stops it."""
        if interval_s is None:
            self._intervals.pop(msg_id, None)
            self._next_due.pop(msg_id, None)
            return
        self._intervals[msg_id] = max(interval_s, MIN_INTERVAL_S)
        self._next_due[msg_id] = now

    def reset_interval(self, msg_id: int, now: float) -> None:
        """Back to the default rate (or off, for a message not streamed by default)."""
        self.set_interval(msg_id, self._defaults.get(msg_id), now)

    def send_soon(self, msg_id: int, now: float) -> None:
        """Bring a streamed message forward to the next tick (e.g. HEARTBEAT on a mode change)."""
        if msg_id in self._next_due:
            self._next_due[msg_id] = min(self._next_due[msg_id], now)

    def next_due(self) -> float | None:
        """When the next message is due, or None if nothing is streamed."""
        return min(self._next_due.values(), default=None)

    def due(self, now: float) -> list[int]:
        """Ids due at ``now``, in a stable order; each is rescheduled one interval on."""
        ready: list[int] = []
        for msg_id, due_at in self._next_due.items():
            if due_at > now:
                continue
            ready.append(msg_id)
            interval = self._intervals[msg_id]
            following = due_at + interval
            # after a stall, resume the rhythm from now rather than sending a burst
            caught_up = following > now - CATCH_UP_S
            self._next_due[msg_id] = following if caught_up else now + interval
        return ready


# -- what clients ask for ---------------------------------------------------------------


class DataStream(IntEnum):
    """MAV_DATA_STREAM: REQUEST_DATA_STREAM's message groups (ArduPilot's SRx_ params)."""

    ALL = 0
    RAW_SENSORS = 1
    EXTENDED_STATUS = 2
    RC_CHANNELS = 3
    RAW_CONTROLLER = 4
    POSITION = 6
    EXTRA1 = 10
    EXTRA2 = 11
    EXTRA3 = 12


# The messages of each group that the simulator sends, as ArduCopter groups them
# (GCS_Common.cpp's STREAM_*_msgs). HEARTBEAT, HOME_POSITION and EXTENDED_SYS_STATE are
# in no group: SET_MESSAGE_INTERVAL is the only way to change their rates.
DATA_STREAM_GROUPS: Mapping[DataStream, tuple[int, ...]] = {
    DataStream.EXTENDED_STATUS: (
        MsgId.SYS_STATUS,
        MsgId.MISSION_CURRENT,
        MsgId.GPS_RAW_INT,
        GPS2_RAW,
    ),
    DataStream.POSITION: (MsgId.GLOBAL_POSITION_INT,),
    DataStream.EXTRA1: (MsgId.ATTITUDE,),
    DataStream.EXTRA2: (MsgId.VFR_HUD,),
    DataStream.EXTRA3: (MsgId.BATTERY_STATUS,),
}


def request_data_stream(
    schedule: StreamSchedule, stream_id: int, rate_hz: int, start_stop: int, now: float
) -> None:
    """GCS_MAVLINK::handle_request_data_stream: start (at ``rate_hz``, 0 stops) or stop
    one group, or every group for MAV_DATA_STREAM_ALL; unknown groups are ignored."""
    if start_stop not in (0, 1):
        return
    rate = float(rate_hz) if start_stop == 1 else 0.0
    if stream_id == DataStream.ALL:
        groups = list(DATA_STREAM_GROUPS)
    else:
        groups = [group for group in DATA_STREAM_GROUPS if group == stream_id]
    for group in groups:
        for msg_id in DATA_STREAM_GROUPS[group]:
            schedule.set_interval(msg_id, 1.0 / rate if rate > 0.0 else None, now)


# Messages ArduPilot knows whether or not the hardware is fitted: their rates can be set
# at any time, and they are sent once the hardware is there.
OPTIONAL_MESSAGES = frozenset({GPS2_RAW})


def set_message_interval(
    schedule: StreamSchedule, msg_id: int, interval_us: float, now: float
) -> None:
    """SET_MESSAGE_INTERVAL's param2: 0 the default rate, negative stops, else microseconds."""
    if interval_us == 0.0:
        schedule.reset_interval(msg_id, now)
    elif interval_us < 0.0:
        schedule.set_interval(msg_id, None, now)
    else:
        schedule.set_interval(msg_id, interval_us / 1e6, now)


class StreamRequests:
    """In front of the message handler: REQUEST_DATA_STREAM, and SET_MESSAGE_INTERVAL
    refused or ignored when the simulator plays an old flight controller."""

    def __init__(
        self, handler: MessageHandler, message_interval: MessageIntervalSupport = "supported"
    ) -> None:
        self.handler = handler
        self.message_interval = message_interval

    def handle(self, msg: Any, streams: StreamSchedule, now: float) -> list[Reply]:
        kind = msg.get_type()
        if kind == "REQUEST_DATA_STREAM":
            if self._for_us(msg):
                request_data_stream(
                    streams,
                    int(msg.req_stream_id),
                    int(msg.req_message_rate),
                    int(msg.start_stop),
                    now,
                )
            return []  # no acknowledgement exists for it
        if (
            kind in ("COMMAND_LONG", "COMMAND_INT")
            and msg.command == MavCmd.SET_MESSAGE_INTERVAL
            and self._for_us(msg)
        ):
            return self._set_message_interval(msg, streams, now)
        return self.handler.handle(msg, streams, now)

    def _set_message_interval(self, msg: Any, streams: StreamSchedule, now: float) -> list[Reply]:
        if self.message_interval == "silent":
            return []
        if self.message_interval == "unsupported":
            return [self._ack(msg, MavResult.UNSUPPORTED)]
        msg_id = int(msg.param1) if math.isfinite(msg.param1) else -1
        if msg_id in OPTIONAL_MESSAGES and msg_id not in self.handler.telemetry.supported:
            set_message_interval(streams, msg_id, float(msg.param2), now)
            return [self._ack(msg, MavResult.ACCEPTED)]
        return self.handler.handle(msg, streams, now)

    def _for_us(self, msg: Any) -> bool:
        return int(msg.target_system) in (0, self.handler.system_id)

    def _ack(self, msg: Any, result: MavResult) -> Reply:
        return Reply(
            self.handler.telemetry.command_ack(
                MavCmd.SET_MESSAGE_INTERVAL, result, msg.get_srcSystem(), msg.get_srcComponent()
            )
        )
