"""Carry out the hub's commands on the flight controller and report its answer.

A command becomes one or more MAVLink commands (`vehicle_agents.fcu.commands`: retries,
COMMAND_ACK, the reason for a refusal), or a mission or parameter exchange; a take-off is
QGroundControl's sequence for the autopilot (guided mode, arm, take off), and a mode change
counts once the autopilot reports the mode.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from protocol.messages import (
    ArmCommand,
    ChangeSpeedCommand,
    Command,
    CommandOutcome,
    DisarmCommand,
    GotoCommand,
    HoldCommand,
    LandCommand,
    ManualStartCommand,
    ManualStopCommand,
    MissionClearCommand,
    MissionDownloadCommand,
    MissionSetCurrentCommand,
    MissionUploadCommand,
    ParamGetCommand,
    ParamListCommand,
    ParamSetCommand,
    RebootCommand,
    ReturnToLaunchCommand,
    SetHomeCommand,
    SetModeCommand,
    TakeoffCommand,
)
from vehicle_agents.fcu.commands import FORCE_DISARM_MAGIC, CommandSender, CommandTimeouts
from vehicle_agents.fcu.link import FcuLink
from vehicle_agents.fcu.messages import LinkChange, MavMessage, next_match
from vehicle_agents.fcu.missions import MissionClient
from vehicle_agents.fcu.modes import ModeSetting, is_armed, mode_name, shows_mode
from vehicle_agents.fcu.params import ParamClient
from vehicle_agents.telemetry.readiness import readiness

log = logging.getLogger(__name__)

# Builds the message for one attempt (COMMAND_LONG counts attempts in `confirmation`).
MessageBuilder = Callable[[int], MavMessage]
GROUND_VEHICLES = frozenset({"rover", "boat", "submarine"})


class CommandRefused(Exception):
    """A step of a multi-step command was refused; carries the outcome to report."""

    def __init__(self, outcome: CommandOutcome) -> None:
        super().__init__(outcome.message)
        self.outcome = outcome


class CommandExecutor(CommandSender):
    """Turns protocol commands into MAVLink exchanges with one flight controller."""

    def __init__(self, link: FcuLink, timeouts: CommandTimeouts | None = None) -> None:
        super().__init__(link, timeouts)
        self.params = ParamClient(link)
        self.missions = MissionClient(link)
        self._reboot_accepted_at: float | None = None  # monotonic
        link.state_listeners.append(self._on_link_change)

    def _on_link_change(self, _change: LinkChange) -> None:
        self._reboot_accepted_at = None  # down or back: the link's own state answers now

    def _rebooting(self) -> bool:
        since = self._reboot_accepted_at
        if since is not None and time.monotonic() - since > self.timeouts.reboot_quiet_s:
            self._reboot_accepted_at = since = None  # it never went quiet: not rebooting
        return since is not None

    async def execute(self, command: Command) -> CommandOutcome:
        if not self.link.connected:
            return CommandOutcome(status="failed", message="flight controller link is down")
        if self._rebooting():
            return CommandOutcome(
                status="failed",
                message=f"{command.name}: the flight controller is rebooting; "
                "wait for its link to come back",
            )
        try:
            return await self._dispatch(command)
        except CommandRefused as refusal:
            return refusal.outcome
        except Exception as error:
            # A command must never take the agent (and the vehicle's link and its hub-link
            # failsafe) down with it: whatever went wrong, it is answered as failed.
            log.exception("command %s failed inside the agent", command.name)
            return CommandOutcome(status="failed", message=f"{command.name}: agent error: {error}")

    async def _dispatch(self, command: Command) -> CommandOutcome:
        match command:
            case ArmCommand():
                return await self.command_long(mavlink2.MAV_CMD_COMPONENT_ARM_DISARM, [1])
            case DisarmCommand(force=force):
                magic = FORCE_DISARM_MAGIC if force else 0
                return await self.command_long(mavlink2.MAV_CMD_COMPONENT_ARM_DISARM, [0, magic])
            case TakeoffCommand(altitude=altitude):
                return await self._takeoff(altitude)
            case LandCommand():
                return await self.command_long(mavlink2.MAV_CMD_NAV_LAND, [])
            case ReturnToLaunchCommand():
                return await self.command_long(mavlink2.MAV_CMD_NAV_RETURN_TO_LAUNCH, [])
            case SetModeCommand(mode=mode):
                return await self._set_mode(mode)
            case GotoCommand(lat=lat, lon=lon, altitude=altitude):
                return await self._goto(lat, lon, altitude)
            case HoldCommand():
                return await self._hold()
            case ChangeSpeedCommand(speed=speed, speed_type=speed_type):
                # param1: 0 airspeed, 1 ground speed; param3 -1 leaves the throttle alone.
                kind = 1 if speed_type == "ground" else 0
                return await self.command_long(mavlink2.MAV_CMD_DO_CHANGE_SPEED, [kind, speed, -1])
            case SetHomeCommand(use_current=True):
                return await self.command_long(mavlink2.MAV_CMD_DO_SET_HOME, [1])
            case SetHomeCommand(lat=float(lat), lon=float(lon), alt_msl=float(alt_msl)):
                # As COMMAND_INT: a float32 COMMAND_LONG parameter holds a latitude only to
                # about a metre. The altitude is above mean sea level, in the frame the
                # autopilot takes it in.
                return await self.command_int(
                    mavlink2.MAV_CMD_DO_SET_HOME, self._amsl_frame(), [0], lat, lon, alt_msl
                )
            case SetHomeCommand():
                return CommandOutcome(
                    status="refused", message="set_home: lat, lon and alt_msl are required"
                )
            case RebootCommand():
                outcome = await self.command_long(mavlink2.MAV_CMD_PREFLIGHT_REBOOT_SHUTDOWN, [1])
                if outcome.status == "accepted":
                    self._reboot_accepted_at = time.monotonic()
                return outcome
            case ParamListCommand():
                return await self.params.read_all()
            case ParamGetCommand(param=name):
                return await self.params.read(name)
            case ParamSetCommand(param=name, value=value):
                return await self.params.write(name, value)
            case MissionUploadCommand(items=items):
                return await self.missions.upload(items)
            case MissionDownloadCommand():
                return await self.missions.download()
            case MissionClearCommand():
                return await self.missions.clear()
            case MissionSetCurrentCommand(seq=seq):
                return await self.missions.set_current(seq)
            case ManualStartCommand() | ManualStopCommand():
                # The agent routes these to its ManualPilot (vehicle_agents/control/manual.py).
                return CommandOutcome(
                    status="refused", message=f"{command.name}: no manual pilot on this agent"
                )

    async def _takeoff(self, altitude: float) -> CommandOutcome:
        modes = self.link.modes
        if modes is not None and modes.vehicle_type in GROUND_VEHICLES:
            return CommandOutcome(
                status="refused", message=f"takeoff: a {modes.vehicle_type} does not take off"
            )
        try:
            if modes is not None and modes.autopilot == "px4":
                outcome = await self._px4_takeoff(altitude)
            else:
                outcome = await self._guided_takeoff(altitude)
        except CommandRefused as refusal:
            outcome = refusal.outcome
        return self._with_readiness(outcome)

    def _with_readiness(self, outcome: CommandOutcome) -> CommandOutcome:
        """A refused take-off also says why the vehicle is not ready to fly (a good GPS
        fix the EKF does not use yet, a failing pre-arm check), when it is not."""
        if outcome.status == "accepted":
            return outcome
        link = self.link
        ready = readiness(link.latest, link.statustexts, time.time())
        if ready.ready is not False or not ready.reason:
            return outcome
        message = f"{outcome.message}; not ready to fly: {ready.reason}"
        return outcome.model_copy(update={"message": message})

    async def _px4_takeoff(self, altitude: float) -> CommandOutcome:
        """What QGroundControl does on PX4: arm, then MAV_CMD_NAV_TAKEOFF, which switches to
        Takeoff mode itself; its altitude is above mean sea level, so home's is needed."""
        home = self.link.latest.get("HOME_POSITION")
        if home is None:
            return CommandOutcome(
                status="refused", message="takeoff: the vehicle has not reported its home yet"
            )
        if not is_armed(self.link.latest.get("HEARTBEAT")):
            _require_accepted(
                await self.command_long(mavlink2.MAV_CMD_COMPONENT_ARM_DISARM, [1]), "arm"
            )
        nan = float("nan")
        amsl = home.altitude / 1000 + altitude
        return await self.command_long(
            mavlink2.MAV_CMD_NAV_TAKEOFF, [-1, 0, 0, nan, nan, nan, amsl]
        )

    async def _guided_takeoff(self, altitude: float) -> CommandOutcome:
        # What QGroundControl does for a guided take-off: guided mode, arm, take off.
        modes = self.link.modes
        guided = modes.guided_mode if modes else None
        if guided is None:
            return CommandOutcome(status="refused", message="vehicle has no guided mode")
        heartbeat = self.link.latest.get("HEARTBEAT")
        if heartbeat is None or mode_name(heartbeat) != guided:
            _require_accepted(await self._set_mode(guided), f"switch to {guided}")
        if not is_armed(self.link.latest.get("HEARTBEAT")):
            _require_accepted(
                await self.command_long(mavlink2.MAV_CMD_COMPONENT_ARM_DISARM, [1]), "arm"
            )
        return await self.command_long(mavlink2.MAV_CMD_NAV_TAKEOFF, [0, 0, 0, 0, 0, 0, altitude])

    async def _hold(self) -> CommandOutcome:
        modes = self.link.modes
        hold = modes.hold_mode if modes else None
        if hold is None:
            return CommandOutcome(status="refused", message="vehicle has no hold mode")
        return await self._set_mode(hold)

    async def _set_mode(self, mode: str) -> CommandOutcome:
        modes = self.link.modes
        setting = modes.settings.get(mode) if modes else None
        if setting is None:
            known = ", ".join(modes.names) if modes else "none"
            return CommandOutcome(
                status="refused", message=f"unknown mode {mode!r}; this vehicle has: {known}"
            )
        outcome = await self.command_long(
            mavlink2.MAV_CMD_DO_SET_MODE,
            [setting.base_mode, setting.custom_mode, setting.custom_sub_mode],
        )
        if outcome.status != "accepted":
            return outcome
        return await self._mode_shown(mode, setting, outcome)

    async def _mode_shown(
        self, mode: str, setting: ModeSetting, accepted: CommandOutcome
    ) -> CommandOutcome:
        """An accepted mode change is a change only once the autopilot reports the mode:
        PX4 accepts OFFBOARD with no setpoint stream and stays where it was. Reported by
        the autopilot's HEARTBEAT or CURRENT_MODE (sent on each change), waited for
        `mode_shown_s` of the autopilot's own clock (its messages' time_boot_ms, so a
        sped-up simulator waits as long in its time), or that long by the agent's clock
        when nothing stamped comes, at most `mode_shown_wall_s`."""
        link = self.link
        autopilot = link.modes.autopilot if link.modes is not None else "generic"

        def shows(message: MavMessage) -> bool:
            return shows_mode(autopilot, int(message.custom_mode), setting)

        def relevant(message: MavMessage) -> bool:
            kind = message.get_type()
            if kind == "HEARTBEAT":
                return bool(message.get_srcComponent() == link.target_component)
            return kind == "CURRENT_MODE" or hasattr(message, "time_boot_ms")

        heartbeat = link.latest.get("HEARTBEAT")
        if heartbeat is not None and shows(heartbeat):
            return accepted
        with link.collect(relevant) as messages:
            started = time.monotonic()
            first_stamp: float | None = None
            while (left := self.timeouts.mode_shown_wall_s - (time.monotonic() - started)) > 0:
                if first_stamp is None and time.monotonic() - started > self.timeouts.mode_shown_s:
                    break  # nothing stamped came: the agent's clock decides
                message = await next_match(messages, left)
                if message is None:
                    break
                if message.get_type() in ("HEARTBEAT", "CURRENT_MODE"):
                    if shows(message):
                        return accepted
                    if message.get_type() == "HEARTBEAT":
                        heartbeat = message
                    continue
                stamp = float(message.time_boot_ms) / 1000
                first_stamp = stamp if first_stamp is None else first_stamp
                if stamp - first_stamp >= self.timeouts.mode_shown_s:
                    break
        stayed = "unknown"
        if heartbeat is not None:
            listed = link.modes.name_of(int(heartbeat.custom_mode)) if link.modes else None
            stayed = listed or mode_name(heartbeat)
        return CommandOutcome(
            status="failed",
            result=accepted.result,
            message=f"{mode}: accepted but the mode stayed {stayed}",
        )

    def _is_px4(self) -> bool:
        return self.link.modes is not None and self.link.modes.autopilot == "px4"

    def _amsl_frame(self) -> int:
        """The COMMAND_INT frame for an altitude above mean sea level. PX4 takes position
        commands only in MAV_FRAME_GLOBAL_INT and answers any other frame with
        MAV_RESULT_COMMAND_UNSUPPORTED_MAV_FRAME; ArduPilot reads MAV_FRAME_GLOBAL and
        GLOBAL_INT alike, and has flown with GLOBAL."""
        return int(mavlink2.MAV_FRAME_GLOBAL_INT if self._is_px4() else mavlink2.MAV_FRAME_GLOBAL)

    def _home_alt_msl(self) -> float | None:
        """Home's altitude above mean sea level: from HOME_POSITION, else from where the
        vehicle is (its altitude less its height above home)."""
        if (home := self.link.latest.get("HOME_POSITION")) is not None:
            return float(home.altitude) / 1000
        if (position := self.link.latest.get("GLOBAL_POSITION_INT")) is not None:
            return float(position.alt - position.relative_alt) / 1000
        return None

    async def _goto(self, lat: float, lon: float, altitude: float) -> CommandOutcome:
        frame = mavlink2.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT  # ArduPilot: above home, as asked
        if self._is_px4():
            # PX4 takes a reposition only above mean sea level (MAV_FRAME_GLOBAL_INT).
            home_alt = self._home_alt_msl()
            if home_alt is None:
                return CommandOutcome(
                    status="refused",
                    message="goto: the vehicle has not reported its home or position yet, "
                    "so the altitude above home cannot be given above sea level",
                )
            frame, altitude = mavlink2.MAV_FRAME_GLOBAL_INT, home_alt + altitude
        return await self.command_int(
            mavlink2.MAV_CMD_DO_REPOSITION,
            frame,
            [
                -1,  # default ground speed
                mavlink2.MAV_DO_REPOSITION_FLAGS_CHANGE_MODE,
                0,
                float("nan"),  # keep the current yaw behaviour
            ],
            lat,
            lon,
            altitude,
        )


def _require_accepted(outcome: CommandOutcome, step: str) -> None:
    if outcome.status != "accepted":
        raise CommandRefused(
            outcome.model_copy(update={"message": f"{step} failed: {outcome.message}"})
        )
