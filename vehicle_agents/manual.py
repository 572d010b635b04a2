"""Flying by hand from the browser: stick frames become MANUAL_CONTROL, with a deadman.

The agent sits next to the aircraft, so the deadman lives here: no fresh frame for
``deadman_s`` (0.5 s) puts the vehicle in its hold mode (Copter BRAKE, Rover HOLD,
Plane LOITER, PX4 AUTO.LOITER) and says so in an event. A dropped hub link stops the
frames, so it ends the same way.

Why MANUAL_CONTROL rather than velocity targets: on ArduPilot it is an RC override of
roll, pitch, throttle and yaw (x pitch, y roll, z throttle 0..1000 with 500 at mid
stick, r yaw), so the vehicle flies in a pilot mode (LOITER here) with the autopilot's
own stick shaping, limits and fences, and the RC transmitter keeps priority. ArduPilot
accepts it only from its GCS (SYSID_MYGCS / MAV_GCS_SYSID, default 255; the agent
speaks as 254, see the README). PX4 accepts it when COM_RC_IN_MODE allows MAVLink
input, and flies it in POSCTL.

Order of authority: a mode change the agent did not make (the RC transmitter's mode
switch, or another GCS) ends browser control at once; frames are ignored from then
until the hub grants a new lease and a fresh stream starts.
"""

from __future__ import annotations

import asyncio
import logging
import time
from collections.abc import Callable
from dataclasses import dataclass

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from protocol.messages import EventKind, HoldCommand, ManualFrame
from vehicle_agents.commands import CommandExecutor
from vehicle_agents.fcu_link import FcuLink, MavMessage
from vehicle_agents.modes import mode_name

log = logging.getLogger(__name__)

EmitEvent = Callable[[EventKind, str, int | None], None]

# The pilot modes that take stick input and hold position when the sticks centre.
PILOT_MODES = ("LOITER", "POSCTL", "MANUAL")


@dataclass(frozen=True)
class ManualTimeouts:
    deadman_s: float = 0.5  # no fresh frame for this long: hold
    check_s: float = 0.05  # how often the deadman looks


class ManualPilot:
    def __init__(
        self,
        link: FcuLink,
        executor: CommandExecutor,
        emit: EmitEvent,
        timeouts: ManualTimeouts | None = None,
        clock: Callable[[], float] = time.monotonic,
    ) -> None:
        self._link = link
        self._executor = executor
        self._emit = emit
        self.timeouts = timeouts or ManualTimeouts()
        self._clock = clock
        self.active = False
        self._last_at = 0.0
        self._last_seq = -1
        self._pilot_mode: str | None = None
        # Set when the RC pilot (or another GCS) took over: frames from this stream on
        # are ignored; a gap in the stream (a new lease) clears it.
        self._overridden = False
        self._seen_pilot_mode = False  # the switch to the pilot mode has shown
        self.sent = 0
        link.listeners.append(self._on_message)

    def on_frame(self, frame: ManualFrame) -> None:
        now = self._clock()
        if self._overridden:
            if now - self._last_at <= self.timeouts.deadman_s:
                self._last_at = now  # the same stream: still ignored
                return
            self._overridden = False
        if self.active and frame.seq <= self._last_seq:
            return  # older than what was flown: never stream a stale value
        if self._link.target_system is None or not self._link.connected:
            # No flight controller to fly: the frame is dropped, and the deadman holds the
            # vehicle if the link comes back after the stream stopped.
            return
        if not self.active:
            self.active = True
            self._last_seq = -1
            self._pilot_mode = self._enter_pilot_mode()
            self._emit("manual", "manual control from the browser started", 5)
        self._last_at = now
        self._last_seq = frame.seq
        axes = frame.axes
        self._link.send(
            mavlink2.MAVLink_manual_control_message(
                self._link.target_system, axes.x, axes.y, axes.z, axes.r, axes.buttons
            )
        )
        self.sent += 1

    def _enter_pilot_mode(self) -> str | None:
        """Switch to a mode that flies stick input (fire and forget: the heartbeat says
        whether it took; MANUAL_CONTROL in another mode is ignored by the autopilot)."""
        modes = self._link.modes
        if modes is None:
            return None
        for name in PILOT_MODES:
            setting = modes.settings.get(name)
            if setting is not None:
                self._link.send_command_long(
                    mavlink2.MAV_CMD_DO_SET_MODE,
                    0,
                    [setting.base_mode, setting.custom_mode, setting.custom_sub_mode],
                )
                return name
        return None

    def _on_message(self, message: MavMessage) -> None:
        if not self.active or message.get_type() != "HEARTBEAT":
            return
        if message.get_srcSystem() != self._link.target_system:
            return
        mode = mode_name(message)
        if self._pilot_mode is not None and self._seen_pilot_mode and mode != self._pilot_mode:
            self.active = False
            self._overridden = True
            self._emit("manual", f"manual control ended: the vehicle changed to {mode}", 4)
        elif mode == self._pilot_mode:
            self._seen_pilot_mode = True

    async def check(self) -> None:
        """The deadman: hold when the stream stopped."""
        if not self.active or self._clock() - self._last_at <= self.timeouts.deadman_s:
            return
        self.active = False
        self._seen_pilot_mode = False
        silence = self._clock() - self._last_at
        log.warning("manual input stopped for %.2f s: holding", silence)
        self._emit("manual", f"manual input stopped for {silence:.2f} s: holding", 4)
        outcome = await self._executor.execute(HoldCommand())
        if outcome.status != "accepted":
            self._emit("manual", f"hold after manual input refused: {outcome.message}", 2)

    async def run(self) -> None:
        while True:
            await self.check()
            await asyncio.sleep(self.timeouts.check_s)
