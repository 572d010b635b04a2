"""How a survey moves its drones: each command through the same path as the operators'
own (audited, rails-checked, ``fleet/command_service.py``), and each drone started on its
uploaded mission as QGroundControl's "Start Mission" starts it for its autopilot."""

from __future__ import annotations

from backend.auth.policy import Principal
from backend.errors import GcsError
from backend.fleet.collaborators import CommandServices
from backend.fleet.command_service import execute_command
from backend.survey.flight.run import DroneRun, SurveyRun
from protocol.messages import (
    ArmCommand,
    Command,
    DisarmCommand,
    ReturnToLaunchCommand,
    SetModeCommand,
    TakeoffCommand,
)
from protocol.mission_rules import mission_mode

SOURCE = "survey"  # the audit log's source for the commands a survey sends


class SurveyCommands:
    def __init__(self, hub: CommandServices) -> None:
        self._hub = hub

    async def send(self, principal: Principal, vehicle_id: str, command: Command) -> str | None:
        """None when the vehicle accepted, else why not."""
        try:
            outcome = await execute_command(self._hub, principal, SOURCE, vehicle_id, command)
        except GcsError as error:
            return error.message if hasattr(error, "message") else str(error)
        return None if outcome.status == "accepted" else outcome.message or outcome.status

    async def launch(self, principal: Principal, run: SurveyRun, drone: DroneRun) -> str | None:
        """Start one drone on its uploaded mission, as QGroundControl's "Start Mission"
        does for its autopilot; None when it is off, else why not (and what was undone).

        Neither autopilot arms itself for a mission. ArduCopter flies AUTO from the ground
        only once "auto armed", which a GCS take-off gives it: a guided take-off (it
        arms), then AUTO. PX4 (PX4FirmwarePlugin::startMission): its mission mode, then
        arm; armed in Mission on the ground with a mission, it takes off on the take-off
        item. The mission mode's name is the one the vehicle's own mode list has."""
        record = self._hub.registry.get(drone.vehicle_id)
        mode = mission_mode(record.modes)
        if mode is None:
            return f"it has no mission mode (its modes: {', '.join(record.modes) or 'none'})"
        if mode != "AUTO":
            return await self._launch_in_mission_mode(principal, drone.vehicle_id, mode)
        why = await self.send(principal, drone.vehicle_id, TakeoffCommand(altitude=run.altitude_m))
        if why is not None:
            return f"take-off: {why}{await self._disarm_on_ground(principal, drone.vehicle_id)}"
        why = await self.send(principal, drone.vehicle_id, SetModeCommand(mode=mode))
        if why is None:
            return None
        # It took off but will not fly the mission: it must not be left hovering.
        back = await self.send(principal, drone.vehicle_id, ReturnToLaunchCommand())
        why += "; sent home" if back is None else f"; RTL also refused: {back}"
        return f"{mode}: {why}"

    async def _launch_in_mission_mode(
        self, principal: Principal, vehicle_id: str, mode: str
    ) -> str | None:
        """PX4: the mission mode, then arm. A refused mode change leaves the drone as it
        was; a refused (or unanswered) arming leaves it on the ground, made sure disarmed."""
        why = await self.send(principal, vehicle_id, SetModeCommand(mode=mode))
        if why is not None:
            return f"{mode}: {why}"
        why = await self.send(principal, vehicle_id, ArmCommand())
        if why is not None:
            return f"arm: {why}{await self._disarm_on_ground(principal, vehicle_id)}"
        return None

    async def _disarm_on_ground(self, principal: Principal, vehicle_id: str) -> str:
        """After a launch step failed once it may have armed: a plain disarm, which both
        autopilots take only on the ground (a flying drone keeps flying), so that nothing
        is left armed on the ground waiting for a mission that will not start. Returns
        what to add to the reason when it did not go through."""
        why = await self.send(principal, vehicle_id, DisarmCommand())
        return "" if why is None else f"; disarm also refused: {why}"
