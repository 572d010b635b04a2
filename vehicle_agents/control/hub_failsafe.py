"""What the vehicle does when the hub has been out of reach for too long.

The flight controller's own failsafes (RC loss, battery, geofence) still apply; this
is the operator's choice for losing the ground station: carry on (a mission flies on
without the hub), hold where it is, or come home. Whatever happened is reported as
flight-log events, which reach the hub with the rest of the outbox once it is back.
"""

from __future__ import annotations

import asyncio
import logging
from collections.abc import Callable
from typing import Literal

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from common.retry import Backoff
from protocol.messages import EventKind, HoldCommand, ReturnToLaunchCommand
from vehicle_agents.control.executor import CommandExecutor
from vehicle_agents.fcu.link import FcuLink
from vehicle_agents.fcu.modes import is_armed, mode_name
from vehicle_agents.sensors.paced_clock import PacedClock

log = logging.getLogger(__name__)

FailsafeAction = Literal["continue", "hold", "rtl"]

# Already coming down or home, often by the autopilot's own failsafe (battery, RC): an
# RTL would climb on a critical battery, a hold would stop a vehicle on its way back.
RECOVERING_MODES = frozenset(
    {"LAND", "RTL", "SMART_RTL", "QLAND", "QRTL", "AUTO.LAND", "AUTO.RTL", "AUTO.PRECLAND"}
)
# Flown by hand on RC: the pilot outranks a ground-station failsafe.
PILOTED_MODES = frozenset(
    {
        "STABILIZE",
        "ALT_HOLD",
        "ACRO",
        "SPORT",
        "DRIFT",
        "FLOWHOLD",
        "MANUAL",
        "STEERING",
        "FBWA",
        "FBWB",
        "CRUISE",
        "TRAINING",
        "QSTABILIZE",
        "QHOVER",
        "QACRO",
        "ALTCTL",
        "POSCTL",
        "STABILIZED",
        "RATTITUDE",
    }
)
EmitEvent = Callable[[EventKind, str, int | None], None]

# Reconnect attempts that fit in the failsafe's timeout, at the least. The hub link's
# jittered backoff grows to 10 s, so after a few drops in a row it could sleep through
# the whole up-time of a flapping field link, and the failsafe would fire on a hub that
# had been back for seconds. Capped at a quarter of the timeout, no up-time longer than
# that cap is missed. Both the timeout and the waits are on the agent's `PacedClock`
# (the autopilot's seconds), so the cap holds at a simulator's speed-up too.
ATTEMPTS_PER_TIMEOUT = 4


def reconnect_backoff(action: FailsafeAction, timeout_s: float, usual: Backoff) -> Backoff:
    """The hub link's reconnect policy under this failsafe: ``usual`` when the failsafe
    does nothing, else capped so that a hub back before the timeout is found in time."""
    if action == "continue":
        return usual
    cap = min(usual.max_s, timeout_s / ATTEMPTS_PER_TIMEOUT)
    return Backoff(initial_s=min(usual.initial_s, cap), max_s=cap)


class HubLinkFailsafe:
    def __init__(
        self,
        connected: asyncio.Event,
        disconnected: asyncio.Event,
        executor: CommandExecutor,
        link: FcuLink,
        emit: EmitEvent,
        action: FailsafeAction,
        timeout_s: float,
        clock: PacedClock | None = None,
    ) -> None:
        # The timeout is counted on the autopilot's clock, never slower than the wall's:
        # a simulator at 4x is failsafed after timeout_s of its flight, and an autopilot
        # whose clock stalls (link lost, board frozen) still after timeout_s of ours.
        self._clock = clock or PacedClock()
        self._connected = connected
        self._disconnected = disconnected
        self._executor = executor
        self._link = link
        self._emit = emit
        self.action = action
        self.timeout_s = timeout_s

    async def run(self) -> None:
        while True:
            await self._disconnected.wait()
            lost_at = self._clock()
            if await self._clock.wait(self._connected, self.timeout_s):
                continue  # a blip, shorter than the timeout: nothing to do or report
            done = await self._act()
            await self._connected.wait()
            outage = self._clock() - lost_at
            self._emit(
                "failsafe",
                f"hub link restored after {outage:.0f} s; on losing it the agent {done}",
                mavlink2.MAV_SEVERITY_NOTICE,
            )

    async def _act(self) -> str:
        """Carry out the configured action; what was done, in words for the log."""
        lost_for = f"hub link lost for {self.timeout_s:g} s"
        heartbeat = self._link.latest.get("HEARTBEAT")
        armed = is_armed(heartbeat)
        mode = mode_name(heartbeat) if heartbeat is not None else "UNKNOWN"
        if self.action == "continue":
            done = "continued (configured action)"
        elif not armed:
            done = f"took no action ({self.action} configured, vehicle disarmed)"
        elif mode in RECOVERING_MODES:
            done = f"took no action ({self.action} configured): the autopilot is in {mode}"
        elif mode in PILOTED_MODES:
            done = f"took no action ({self.action} configured): a pilot flies it in {mode}"
        else:
            command = HoldCommand() if self.action == "hold" else ReturnToLaunchCommand()
            outcome = await self._executor.execute(command)
            verb = "commanded" if outcome.status == "accepted" else "could not command"
            done = f"{verb} {self.action.upper()} ({outcome.message})"
        log.warning("%s: %s", lost_for, done)
        severity = mavlink2.MAV_SEVERITY_WARNING if armed else mavlink2.MAV_SEVERITY_NOTICE
        self._emit("failsafe", f"{lost_for}: {done}", severity)
        return done
