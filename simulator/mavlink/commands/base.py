"""What every family of message handlers shares: the decoded command, the replies, and
the handler's vehicle, telemetry builder and way of answering."""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass
from typing import Any

from simulator.mavconst import MavCmd, MavFrame, MavResult
from simulator.mavlink.message_context import MavMessage
from simulator.mavlink.telemetry import TelemetryBuilder
from simulator.vehicle import Vehicle

log = logging.getLogger("simulator.mavlink.commands")

INT32_MAX = 2**31 - 1


@dataclass(frozen=True)
class Reply:
    message: MavMessage
    to_sender_only: bool = True


@dataclass(frozen=True)
class Command:
    """COMMAND_LONG or COMMAND_INT, in COMMAND_INT's terms."""

    command: int
    param1: float
    param2: float
    param3: float
    param4: float
    x: float  # latitude in degrees for global frames (COMMAND_INT's x / 1e7)
    y: float
    z: float
    frame: int
    x_unset: bool = False  # COMMAND_INT sent INT32_MAX / COMMAND_LONG sent NaN
    raw_y: float = 0.0  # param6 as sent, for commands where it is a number, not a position

    @classmethod
    def from_long(cls, msg: Any) -> Command:
        command = int(msg.command)
        # DO_SET_HOME's altitude is above mean sea level; the rest are above home
        frame = MavFrame.GLOBAL if command == MavCmd.DO_SET_HOME else MavFrame.GLOBAL_RELATIVE_ALT
        return cls(
            command,
            float(msg.param1),
            float(msg.param2),
            float(msg.param3),
            float(msg.param4),
            float(msg.param5),
            float(msg.param6),
            float(msg.param7),
            frame,
            x_unset=math.isnan(msg.param5) or math.isnan(msg.param6),
            raw_y=float(msg.param6),
        )

    @classmethod
    def from_int(cls, msg: Any) -> Command:
        return cls(
            int(msg.command),
            float(msg.param1),
            float(msg.param2),
            float(msg.param3),
            float(msg.param4),
            int(msg.x) / 1e7,
            int(msg.y) / 1e7,
            float(msg.z),
            int(msg.frame),
            x_unset=int(msg.x) == INT32_MAX or int(msg.y) == INT32_MAX,
            raw_y=float(msg.y),
        )


class HandlerBase:
    """One vehicle's link to its GCSs: what every message family answers through."""

    def __init__(
        self,
        copter: Vehicle,
        telemetry: TelemetryBuilder,
        system_id: int,
        component_id: int = 1,
    ) -> None:
        self.copter = copter
        self.telemetry = telemetry
        self.system_id = system_id
        self.component_id = component_id

    def _for_us(self, target_system: int) -> bool:
        return target_system in (0, self.system_id)

    def _finish(self, command: int, result: MavResult, msg: Any) -> list[Reply]:
        """STATUSTEXTs the command caused, then its COMMAND_ACK to the sender."""
        if result is not MavResult.ACCEPTED:
            log.info("command %d from sysid %d: %s", command, msg.get_srcSystem(), result.name)
        ack = self.telemetry.command_ack(
            command, result, msg.get_srcSystem(), msg.get_srcComponent()
        )
        return [*self._texts(), Reply(ack)]

    def _texts(self) -> list[Reply]:
        replies = []
        for text in self.copter.drain_texts():
            log.info("STATUSTEXT %s: %s", text.severity.name, text.text)
            replies.append(Reply(self.telemetry.statustext(text), to_sender_only=False))
        return replies


def as_int(value: float) -> int:
    return int(value) if math.isfinite(value) else -1
