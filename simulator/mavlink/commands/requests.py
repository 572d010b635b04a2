"""Requested messages and telemetry intervals: REQUEST_MESSAGE, GET_HOME_POSITION,
REQUEST_AUTOPILOT_CAPABILITIES, SET_MESSAGE_INTERVAL and GET_MESSAGE_INTERVAL."""

from __future__ import annotations

from typing import Protocol

from simulator.mavconst import MavResult
from simulator.mavlink.commands.base import Command, HandlerBase, Reply, as_int


class StreamControl(Protocol):
    """The sending connection's telemetry schedule (for SET/GET_MESSAGE_INTERVAL)."""

    def interval(self, msg_id: int) -> float | None: ...

    def set_interval(self, msg_id: int, interval_s: float | None, now: float) -> None: ...

    def reset_interval(self, msg_id: int, now: float) -> None: ...


class Requests(HandlerBase):
    """GCS_MAVLINK's answers to requests for messages and for their rates."""

    def _message_interval(self, cmd: Command, streams: StreamControl) -> Reply:
        """MESSAGE_INTERVAL for GET_MESSAGE_INTERVAL: -1 if stopped, 0 if not supported."""
        msg_id = as_int(cmd.param1)
        interval = streams.interval(msg_id)
        interval_us = -1 if interval is None else round(interval * 1e6)
        if msg_id not in self.telemetry.supported:
            interval_us = 0
        return Reply(self.telemetry.message_interval(msg_id, interval_us))

    def _set_message_interval(self, cmd: Command, streams: StreamControl, now: float) -> MavResult:
        msg_id = as_int(cmd.param1)
        if msg_id not in self.telemetry.supported:
            return MavResult.DENIED
        interval_us = cmd.param2
        if interval_us == 0.0:
            streams.reset_interval(msg_id, now)
        elif interval_us < 0.0:
            streams.set_interval(msg_id, None, now)
        else:
            streams.set_interval(msg_id, interval_us / 1e6, now)
        return MavResult.ACCEPTED
