"""Flying by hand from the browser: stick frames become MANUAL_CONTROL, with a deadman.

Browser control opens only when the hub grants a lease (``manual_start``): the agent
first checks that the autopilot will take MANUAL_CONTROL from it
(`vehicle_agents/control/manual_readiness.py`), and refuses with the reason instead of
streaming frames the autopilot would drop.

It then switches to a pilot mode (ArduPilot LOITER, PX4 POSCTL), which pauses a mission
in progress; the mission resumes from the same item when its mode (AUTO) is set again.
Centred sticks at mid throttle (x, y, r 0, z 500: hold position and height) stream at
the stream's rate from the start, before and after the switch, until the browser's
first frame: PX4 refuses POSCTL in the air (TEMPORARILY_REJECTED) before it has had
manual input, and ArduPilot in LOITER flies the RC transmitter's throttle until an
override comes, so a low one sinks the copter while the first frame is on its way.

The agent sits next to the aircraft, so the deadman lives here: no fresh frame for
``deadman_s`` (0.5 s) puts the vehicle in its hold mode (Copter BRAKE, Rover HOLD,
Plane LOITER, PX4 AUTO.LOITER) and says so in an event. A dropped hub link stops the
frames, so it ends the same way. A "gamepad" or "program" stream that repeats the same
off-centre values for ``frozen_s`` is a frozen device (or a client streaming its last
reading) and holds the vehicle too: a live analogue stick is never bit-identical for
long, while a key or an on-screen stick held still is, so those two are left to the
page's own liveness (it stops sending when hidden, blurred or the pointer is lost).

Why MANUAL_CONTROL rather than velocity targets: on ArduPilot it is an RC override of
roll, pitch, throttle and yaw (x pitch, y roll, z throttle 0..1000 with 500 at mid
stick, r yaw), so the vehicle flies in a pilot mode with the autopilot's own stick
shaping, limits and fences, and the RC transmitter keeps priority; PX4 flies it in
POSCTL the same way. Velocity targets (SET_POSITION_TARGET_LOCAL_NED in GUIDED/OFFBOARD)
would bypass the transmitter's priority and need a 2 Hz-or-faster stream of their own.

Order of authority: a mode change the agent did not make (the RC transmitter's mode
switch, or another GCS) ends browser control at once; the hub then ends the lease.

Buttons (MANUAL_CONTROL's bitmask, acted on when pressed): bit 0 "select" as the seed
framework's controller did it (below 3 m: land, or disarm on the ground, when the
motors run; arm when they do not; ignored higher up), bit 1 "hold" (hold and give back
control).
"""

from __future__ import annotations

import asyncio
import logging
import time
from collections.abc import Callable
from dataclasses import dataclass

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from protocol.messages import (
    ArmCommand,
    CommandOutcome,
    DisarmCommand,
    EventKind,
    HoldCommand,
    LandCommand,
    ManualApplied,
    ManualFrame,
    SetModeCommand,
)
from protocol.mission_rules import MISSION_MODES
from vehicle_agents.control.executor import CommandExecutor
from vehicle_agents.control.manual_readiness import manual_refusal
from vehicle_agents.fcu.link import FcuLink
from vehicle_agents.fcu.messages import MavMessage
from vehicle_agents.fcu.modes import is_armed, mode_name

log = logging.getLogger(__name__)

EmitEvent = Callable[[EventKind, str, int | None], None]

# The pilot modes that take stick input and hold position when the sticks centre, per
# autopilot: PX4's "LOITER" (AUTO.LOITER, Hold) flies no sticks, its POSCTL does.
PILOT_MODES = {"ardupilot": ("LOITER", "MANUAL"), "px4": ("POSCTL",)}
BUTTON_SELECT = 1 << 0
BUTTON_HOLD = 1 << 1
SELECT_BELOW_M = 3.0  # the seed's select button acts only this close to the ground
# Sources whose values must keep changing (see the module's docstring).
FREEZABLE_SOURCES = ("gamepad", "program")
MID_THROTTLE = 500
ENDED_SEVERITY = 4  # WARNING: the hub ends the lease on a manual event this severe


@dataclass(frozen=True)
class ManualTimeouts:
    deadman_s: float = 0.5  # no fresh frame for this long: hold
    first_frame_s: float = 3.0  # from the lease's start to the first frame
    frozen_s: float = 3.0  # a gamepad's same off-centre values this long: hold
    check_s: float = 0.05  # how often the deadman looks
    echo_s: float = 0.5  # how often a flown frame is echoed to the pilot (its delay)
    centre_period_s: float = 0.04  # centred sticks at 25 Hz, the stream's rate
    prime_s: float = 0.2  # centred sticks this long before the mode switch
    switch_s: float = 1.5  # a switch TEMPORARILY_REJECTED is tried again this long


def _off_centre(frame: ManualFrame) -> bool:
    axes = frame.axes
    return bool(axes.x or axes.y or axes.r or axes.z != MID_THROTTLE)


class ManualPilot:
    def __init__(
        self,
        link: FcuLink,
        executor: CommandExecutor,
        emit: EmitEvent,
        timeouts: ManualTimeouts | None = None,
        clock: Callable[[], float] = time.monotonic,
        source_system: int = 254,
        wall: Callable[[], float] = time.monotonic,
    ) -> None:
        self._link = link
        self._executor = executor
        self._emit = emit
        self.timeouts = timeouts or ManualTimeouts()
        # The deadman and the frozen-input watch count the autopilot's seconds (the agent's
        # `PacedClock`: a simulator at 4x flies four times as far on a stale stick in a
        # wall second), never fewer than the wall's; the first frame's grace is the wall's,
        # as the hub's lease expiry it outlasts.
        self._clock = clock
        self._wall = wall
        self._first_frame_by = 0.0
        self._source_system = source_system
        self.active = False  # browser control is open (a lease started it)
        self._last_at = 0.0  # the last fresh frame (or the start, plus its grace)
        self._last_seq = -1
        self._last_values: tuple[int, int, int, int, int] | None = None
        self._changed_at = 0.0
        self._frozen_source = False
        self._buttons = 0
        self._pressed: list[int] = []  # button bits pressed, acted on by check()
        self._pilot_mode: str | None = None
        self._seen_pilot_mode = False  # the switch to the pilot mode has shown
        self._echoed_at = -1e9
        self._centring: asyncio.Task[None] | None = None
        self.sent = 0
        self.ignored = 0  # frames that came with no browser control open
        link.listeners.append(self._on_message)

    # -- the lease's start and end, from the hub ------------------------------------

    async def start(self) -> CommandOutcome:
        """Open browser control: check the autopilot will take it, enter the pilot mode."""
        refusal = await manual_refusal(self._link, self._executor.params, self._source_system)
        if refusal is not None:
            why, fix = refusal
            return CommandOutcome(status="refused", message=f"manual control: {why}", fix=fix)
        modes = self._link.modes
        candidates = PILOT_MODES.get(modes.autopilot, ()) if modes is not None else ()
        pilot_mode = next((m for m in candidates if modes and m in modes.settings), None)
        if pilot_mode is None:
            return CommandOutcome(
                status="refused", message="manual control: the vehicle has no pilot mode"
            )
        heartbeat = self._link.latest.get("HEARTBEAT")
        before = mode_name(heartbeat) if heartbeat is not None else None
        # Open before the mode change, so that the heartbeat showing the pilot mode (it
        # may come with the ACK) is seen, and any later change ends browser control.
        self._pilot_mode = pilot_mode
        self._seen_pilot_mode = before == pilot_mode
        self._last_seq = -1
        self._last_values = None
        self._buttons = 0
        self._pressed.clear()
        now = self._clock()
        # The deadman's clock starts with a grace for the stream's first frame (longer
        # than the hub's lease expiry, which ends a lease that never streams first).
        self._last_at = now
        self._first_frame_by = self._wall() + self.timeouts.first_frame_s
        self._changed_at = now
        self.active = True
        self._start_centring()
        await asyncio.sleep(self.timeouts.prime_s)  # the autopilot sees manual input
        if before != pilot_mode:
            outcome = await self._switch(pilot_mode)
            if outcome.status != "accepted":
                self.active = False
                self._stop_centring()
                return CommandOutcome(
                    status="refused",
                    message=f"manual control: {pilot_mode} refused: {outcome.message}",
                    result=outcome.result,
                )
            # Accepted: the autopilot is in the pilot mode now, and a heartbeat it sent
            # before the ACK came before the ACK on the same link, so any other mode
            # from here on is someone else's change.
            self._seen_pilot_mode = True
        paused = before if before in MISSION_MODES else None
        text = f"manual control from the browser started in {pilot_mode}"
        if paused is not None:
            text += f"; the mission is paused ({paused} resumes it)"
        self._emit("manual", text, 5)
        return CommandOutcome(
            status="accepted",
            message=text,
            values={"mission_paused": 1.0} if paused is not None else None,
        )

    async def _switch(self, pilot_mode: str) -> CommandOutcome:
        """The mode change, tried again while PX4 says TEMPORARILY_REJECTED (it has not
        seen the centred sticks yet) for up to ``switch_s``."""
        give_up_at = self._clock() + self.timeouts.switch_s
        while True:
            outcome = await self._executor.execute(SetModeCommand(mode=pilot_mode))
            retry = outcome.result == "MAV_RESULT_TEMPORARILY_REJECTED" and self.active
            if not retry or self._clock() >= give_up_at:
                return outcome
            await asyncio.sleep(self.timeouts.prime_s)

    def _start_centring(self) -> None:
        self._stop_centring()
        self._centring = asyncio.get_running_loop().create_task(self._centre())

    def _stop_centring(self) -> None:
        if self._centring is not None:
            self._centring.cancel()
            self._centring = None

    async def _centre(self) -> None:
        """Centred sticks, mid throttle, until the browser's first frame or the end."""
        while self.active and self._last_seq < 0:
            target = self._link.target_system
            if target is not None and self._link.connected:
                self._link.send(
                    mavlink2.MAVLink_manual_control_message(target, 0, 0, MID_THROTTLE, 0, 0)
                )
            await asyncio.sleep(self.timeouts.centre_period_s)

    async def stop(self) -> CommandOutcome:
        """The lease was given back: the vehicle holds where it is."""
        self._stop_centring()
        if not self.active:
            return CommandOutcome(status="accepted", message="manual control was not open")
        self.active = False
        self._emit("manual", "manual control from the browser released: holding", 5)
        return await self._executor.execute(HoldCommand())

    # -- the stream -----------------------------------------------------------------

    def on_frame(self, frame: ManualFrame) -> ManualApplied | None:
        """Fly one frame; now and then, what to tell the hub about it (its echo)."""
        if not self.active or self._link.target_system is None:
            self.ignored += 1  # nothing takes control without a lease
            return None
        if frame.seq <= self._last_seq:
            return None  # older than what was flown: never stream a stale value
        if not self._link.connected:
            # No flight controller to fly: the frame is dropped, and the deadman holds the
            # vehicle if the link comes back after the stream stopped.
            return None
        self._stop_centring()  # the browser flies from here
        now = self._clock()
        axes = frame.axes
        values = (axes.x, axes.y, axes.z, axes.r, axes.buttons)
        if values != self._last_values or not _off_centre(frame):
            self._changed_at = now
        self._last_values = values
        self._frozen_source = frame.source in FREEZABLE_SOURCES
        self._last_at = now
        self._last_seq = frame.seq
        pressed = axes.buttons & ~self._buttons
        self._buttons = axes.buttons
        if pressed:
            self._pressed.append(pressed)
        self._link.send(
            mavlink2.MAVLink_manual_control_message(
                self._link.target_system, axes.x, axes.y, axes.z, axes.r, axes.buttons
            )
        )
        self.sent += 1
        if now - self._echoed_at < self.timeouts.echo_s:
            return None
        self._echoed_at = now
        return ManualApplied(seq=frame.seq, sent_ms=frame.sent_ms)

    def _on_message(self, message: MavMessage) -> None:
        if not self.active or message.get_type() != "HEARTBEAT":
            return
        if message.get_srcSystem() != self._link.target_system:
            return
        mode = mode_name(message)
        if self._pilot_mode is not None and self._seen_pilot_mode and mode != self._pilot_mode:
            self.active = False
            self._emit("manual", f"manual control ended: the vehicle changed to {mode}", 4)
        elif mode == self._pilot_mode:
            self._seen_pilot_mode = True

    async def check(self) -> None:
        """The deadman and the frozen-input watch; the buttons pressed since last time."""
        if not self.active:
            return
        now = self._clock()
        silence = now - self._last_at
        first_frame_due = self._last_seq >= 0 or self._wall() > self._first_frame_by
        if silence > self.timeouts.deadman_s and first_frame_due:
            await self._hold(f"manual input stopped for {silence:.2f} s: holding")
            return
        if self._frozen_source and now - self._changed_at > self.timeouts.frozen_s:
            await self._hold(
                f"manual input frozen: the same off-centre values for "
                f"{now - self._changed_at:.1f} s: holding"
            )
            return
        while self._pressed and self.active:
            await self._button(self._pressed.pop(0))

    async def _hold(self, why: str) -> None:
        self.active = False
        self._stop_centring()
        log.warning("%s", why)
        self._emit("manual", why, ENDED_SEVERITY)
        outcome = await self._executor.execute(HoldCommand())
        if outcome.status != "accepted":
            self._emit("manual", f"hold after manual input refused: {outcome.message}", 2)

    async def _button(self, pressed: int) -> None:
        if pressed & BUTTON_HOLD:
            await self._hold("hold button pressed: holding, manual control given back")
            return
        if not pressed & BUTTON_SELECT:
            return
        heartbeat = self._link.latest.get("HEARTBEAT")
        position = self._link.latest.get("GLOBAL_POSITION_INT")
        altitude = position.relative_alt / 1000.0 if position is not None else 0.0
        if altitude >= SELECT_BELOW_M:
            self._emit("manual", f"select ignored at {altitude:.1f} m (acts below 3 m)", 5)
            return
        if not is_armed(heartbeat):
            outcome = await self._executor.execute(ArmCommand())
            action = "arm"
        elif self._executor.airborne():
            # ArduPilot and PX4 disarm by themselves once landed.
            outcome = await self._executor.execute(LandCommand())
            action = "land"
        else:
            outcome = await self._executor.execute(DisarmCommand())
            action = "disarm"
        self._emit("manual", f"select: {action}: {outcome.message}", 5)

    async def run(self) -> None:
        while True:
            await self.check()
            await asyncio.sleep(self.timeouts.check_s)
