"""What the hub checks against the mission on board before a command that depends on it:
a switch to the mission mode flies only a mission that passed the mission check, and a
new current item must be one of the mission's.

Both read the vehicle's own mission (a download), not the hub's memory of what it sent:
another GCS may have loaded a different one.
"""

from __future__ import annotations

import asyncio

from backend.errors import CommandTimedOut, InvalidRequest, VehicleRefused
from backend.fleet.collaborators import MissionServices
from backend.fleet.registry import VehicleRecord
from backend.safety import Violation
from backend.safety.rails import MISSION_UNCHECKED
from protocol.messages import (
    Command,
    MissionDownloadCommand,
    MissionItem,
    MissionSetCurrentCommand,
    SetModeCommand,
)

# The modes that fly the stored mission: ArduPilot's AUTO (every vehicle type), PX4's
# AUTO.MISSION.
MISSION_MODES = frozenset({"AUTO", "AUTO.MISSION"})


def starts_mission(command: Command) -> bool:
    return isinstance(command, SetModeCommand) and command.mode.upper() in MISSION_MODES


async def on_board_mission(hub: MissionServices, vehicle_id: str) -> list[MissionItem]:
    """The vehicle's mission now, without home (item 1 first). Raises GcsError when it
    cannot be read (VehicleRefused, or the dispatcher's own errors)."""
    outcome = await hub.dispatcher.execute(vehicle_id, MissionDownloadCommand())
    if outcome.status != "accepted" or outcome.items is None:
        raise VehicleRefused(f"mission download: {outcome.message}")
    return list(outcome.items[1:])


async def unchecked_mission(
    hub: MissionServices, record: VehicleRecord
) -> tuple[list[Violation], int]:
    """Every problem of the mission on board (the mission check, as for an upload), and
    its number of items; a mission that cannot be read or is empty is a violation too."""
    try:
        items = await on_board_mission(hub, record.id)
    except (VehicleRefused, CommandTimedOut) as error:  # offline: the switch fails anyway
        reason = f"the mission on board could not be read to check it: {error.message}"
        return [Violation(MISSION_UNCHECKED, reason)], 0
    if not items:
        return [Violation(MISSION_UNCHECKED, "the vehicle holds no mission to fly")], 0
    check = await asyncio.to_thread(hub.safety.check_mission, record, items)
    return list(check.violations), len(items)


async def check_current_item(hub: MissionServices, record: VehicleRecord, command: Command) -> None:
    """Refuse at once a current item beyond the mission, naming its length.

    The vehicle's MISSION_CURRENT.total is trusted to let an item through; an item beyond
    it (or an unknown total) is confirmed against the mission on board first, since the
    total trails a fresh upload by up to a telemetry period."""
    if not isinstance(command, MissionSetCurrentCommand):
        return
    total = record.state.mission_total if record.state else None
    if total is not None and command.seq <= total:
        return
    count = len(await on_board_mission(hub, record.id))
    if command.seq > count:
        held = f"it has {count} items (1..{count})" if count else "it holds no mission"
        raise InvalidRequest("seq", f"item {command.seq} is not in the mission: {held}")
