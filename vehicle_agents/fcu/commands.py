"""One MAVLink command sent to the flight controller, answered by its COMMAND_ACK.

Each command is sent with retries and waits for the matching COMMAND_ACK. An ACK of
MAV_RESULT_IN_PROGRESS ends the retries (the autopilot has the command) and the wait goes
on, bounded by a longer timeout, for the final ACK, whose result is reported. A refusal
comes back with the STATUSTEXT the autopilot sent alongside it (for example the failed
pre-arm check), because "FAILED" alone tells an operator nothing; where an autopilot
refuses without a word (ArduPilot declines a plain disarm in flight and a reboot while
armed silently) the sender says what the vehicle's state points to.
"""

from __future__ import annotations

import asyncio
import logging
import time
from collections.abc import Callable
from dataclasses import dataclass

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from protocol.messages import CommandOutcome
from vehicle_agents.fcu.link import FcuLink
from vehicle_agents.fcu.messages import MavMessage, next_match
from vehicle_agents.fcu.modes import is_armed
from vehicle_agents.fcu.results import result_name

log = logging.getLogger(__name__)

# Builds the message for one attempt (COMMAND_LONG counts attempts in `confirmation`).
MessageBuilder = Callable[[int], MavMessage]
FORCE_DISARM_MAGIC = 21196  # ArduPilot and PX4 skip their checks with this param2
_AIRBORNE = frozenset(
    {
        mavlink2.MAV_LANDED_STATE_IN_AIR,
        mavlink2.MAV_LANDED_STATE_TAKEOFF,
        mavlink2.MAV_LANDED_STATE_LANDING,
    }
)
_PROGRESS_UNKNOWN = 255


@dataclass(frozen=True)
class CommandTimeouts:
    ack_s: float = 1.5  # one attempt's wait for COMMAND_ACK
    attempts: int = 3
    # After MAV_RESULT_IN_PROGRESS, how long the final COMMAND_ACK may take. Within the
    # hub's command timeout (15 s by default) even when the first attempts went unheard.
    in_progress_s: float = 10.0
    # After an accepted reboot the autopilot goes quiet, but the link is only seen down
    # after a heartbeat timeout: commands in between would wait out every retry for an
    # answer that cannot come. They are refused at once for this long, or until the link
    # has gone down (the link-down answer takes over) or come back.
    reboot_quiet_s: float = 5.0
    # After an accepted mode change, how long the autopilot has to report the new mode
    # (seconds of its own clock), and the most the agent waits for that by its own.
    mode_shown_s: float = 2.0
    mode_shown_wall_s: float = 6.0


def _command_name(command: int) -> str:
    entry = mavlink2.enums["MAV_CMD"].get(command)
    return entry.name if entry is not None else f"command {command}"


class CommandSender:
    """Sends MAVLink commands to one flight controller and waits for their answer."""

    def __init__(self, link: FcuLink, timeouts: CommandTimeouts | None = None) -> None:
        self.link = link
        self.timeouts = timeouts or CommandTimeouts()

    async def command_int(
        self, command: int, frame: int, params: list[float], lat: float, lon: float, alt: float
    ) -> CommandOutcome:
        """A command with a position, which COMMAND_INT carries at full precision."""
        padded = [float(value) for value in params] + [0.0] * (4 - len(params))
        link = self.link
        message = mavlink2.MAVLink_command_int_message(
            link.target_system or 1,
            link.target_component,
            frame,
            command,
            0,  # current: unused
            0,  # autocontinue: unused
            *padded,
            round(lat * 1e7),
            round(lon * 1e7),
            alt,
        )
        return await self._exchange(command, lambda _attempt: message, padded)

    async def command_long(self, command: int, params: list[float]) -> CommandOutcome:
        padded = [float(value) for value in params] + [0.0] * (7 - len(params))
        link = self.link

        def build(attempt: int) -> MavMessage:
            return mavlink2.MAVLink_command_long_message(
                link.target_system or 1, link.target_component, command, attempt, *padded
            )

        return await self._exchange(command, build, padded)

    async def _exchange(
        self, command: int, build: MessageBuilder, params: list[float] | None = None
    ) -> CommandOutcome:
        name = _command_name(command)
        started = time.time()
        # One queue for the whole exchange: a late ACK to an earlier attempt still counts,
        # and a final ACK arriving right behind IN_PROGRESS is not missed.
        with self.link.collect(_ack_of(command)) as acks:
            for attempt in range(self.timeouts.attempts):
                self.link.send(build(attempt))
                ack = await next_match(acks, self.timeouts.ack_s)
                if ack is None:
                    log.debug("%s: no COMMAND_ACK on attempt %d", name, attempt + 1)
                elif ack.result == mavlink2.MAV_RESULT_IN_PROGRESS:
                    # the autopilot has it: sending it again would start it again
                    return await self._final_ack(name, acks, ack, started, params)
                else:
                    return self._outcome(name, ack, started, params)
        waited = self.timeouts.ack_s * self.timeouts.attempts
        return CommandOutcome(
            status="timeout",
            message=f"{name}: no COMMAND_ACK from the flight controller after "
            f"{self.timeouts.attempts} attempts ({waited:.1f} s)",
        )

    async def _final_ack(
        self,
        name: str,
        acks: asyncio.Queue[MavMessage],
        first: MavMessage,
        started: float,
        params: list[float] | None,
    ) -> CommandOutcome:
        """Wait out MAV_RESULT_IN_PROGRESS for the COMMAND_ACK that ends the command."""
        progress = _progress(first)
        log.info("%s: in progress%s", name, _percent(progress))
        limit = self.timeouts.in_progress_s
        deadline = time.monotonic() + limit
        while (remaining := deadline - time.monotonic()) > 0:
            ack = await next_match(acks, remaining)
            if ack is None:
                break
            if ack.result != mavlink2.MAV_RESULT_IN_PROGRESS:
                log.info("%s: finished: %s", name, result_name(ack.result))
                return self._outcome(name, ack, started, params)
            if _progress(ack) != progress:
                progress = _progress(ack)
                log.info("%s: in progress%s", name, _percent(progress))
        return CommandOutcome(
            status="timeout",
            result=result_name(mavlink2.MAV_RESULT_IN_PROGRESS),
            message=f"{name}: the flight controller said it was in progress"
            f"{_percent(progress)} but sent no final COMMAND_ACK within {limit:.1f} s",
        )

    def _outcome(
        self, name: str, ack: MavMessage, started: float, params: list[float] | None = None
    ) -> CommandOutcome:
        result = result_name(ack.result)
        if ack.result == mavlink2.MAV_RESULT_ACCEPTED:
            return CommandOutcome(status="accepted", result=result, message=f"{name}: accepted")
        # The autopilot explains a refusal in a STATUSTEXT (e.g. a failed pre-arm check)
        # sent alongside the ACK; informational chatter is not an explanation.
        reasons = [
            entry.text
            for entry in self.link.statustexts
            if entry.time >= started and entry.severity <= mavlink2.MAV_SEVERITY_WARNING
        ]
        if reasons:
            reason = f" ({'; '.join(reasons)})"
        elif (likely := self._likely_reason(int(ack.command), params or [])) is not None:
            reason = f" (no reason from the autopilot; {likely})"
        else:
            reason = ""
        return CommandOutcome(status="refused", result=result, message=f"{name}: {result}{reason}")

    def _likely_reason(self, command: int, params: list[float]) -> str | None:
        """What the vehicle's state says about a refusal the autopilot did not explain."""
        heartbeat = self.link.latest.get("HEARTBEAT")
        if not is_armed(heartbeat):
            return None
        if command == mavlink2.MAV_CMD_PREFLIGHT_REBOOT_SHUTDOWN:
            return "the vehicle is armed, and autopilots refuse to reboot while armed"
        plain_disarm = params[:2] == [0.0, 0.0]
        if command == mavlink2.MAV_CMD_COMPONENT_ARM_DISARM and plain_disarm and self.airborne():
            return (
                "the vehicle is in the air, and a plain disarm is refused in flight; "
                "a forced disarm stops the motors"
            )
        return None

    def airborne(self) -> bool:
        state = self.link.latest.get("EXTENDED_SYS_STATE")
        if state is not None and state.landed_state != mavlink2.MAV_LANDED_STATE_UNDEFINED:
            return int(state.landed_state) in _AIRBORNE
        position = self.link.latest.get("GLOBAL_POSITION_INT")
        return position is not None and position.relative_alt > 1000  # 1 m above home


def _ack_of(command: int) -> Callable[[MavMessage], bool]:
    def matches(message: MavMessage) -> bool:
        return bool(message.get_type() == "COMMAND_ACK" and message.command == command)

    return matches


def _progress(ack: MavMessage) -> int:
    """COMMAND_ACK.progress (a MAVLink 2 extension): percent done, 255 when unknown."""
    return int(getattr(ack, "progress", _PROGRESS_UNKNOWN))


def _percent(progress: int) -> str:
    return f" ({progress}%)" if 0 <= progress <= 100 else ""
