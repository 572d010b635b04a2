"""What the hub checks against the mission on board before a command that depends on it:
a switch to the mission mode flies only a mission that passed the mission check, and a
new current item must be one of the mission's (the rules: `backend.missions.gate`).

Both read the vehicle's own mission (a download), not the hub's memory of what it sent:
another GCS may have loaded a different one.
"""

from __future__ import annotations

import asyncio

from backend.auth.policy import Principal
from backend.errors import CommandTimedOut, InvalidRequest, VehicleRefused
from backend.fleet.collaborators import MissionServices
from backend.fleet.commands import Sender
from backend.fleet.registry import VehicleRecord
from backend.missions.gate import (
    current_item_problem,
    current_item_trusted,
    nothing_to_fly,
    unreadable,
)
from backend.safety import Violation
from protocol.messages import (
    Command,
    MissionDownloadCommand,
    MissionItem,
    MissionSetCurrentCommand,
)


async def on_board_mission(
    hub: MissionServices, vehicle_id: str, principal: Principal
) -> list[MissionItem]:
    """The vehicle's mission now, without home (item 1 first), read for ``principal``.
    Raises GcsError when it cannot be read (VehicleRefused, or the dispatcher's own
    errors)."""
    sender = Sender(principal, "mission_check")
    outcome = await hub.dispatcher.execute(vehicle_id, MissionDownloadCommand(), sender)
    if outcome.status != "accepted" or outcome.items is None:
        raise VehicleRefused(f"mission download: {outcome.message}")
    return list(outcome.items[1:])


async def unchecked_mission(
    hub: MissionServices, record: VehicleRecord, principal: Principal
) -> tuple[list[Violation], int]:
    """Every problem of the mission on board (the mission check, as for an upload), and
    its number of items; a mission that cannot be read or is empty is a violation too."""
    try:
        items = await on_board_mission(hub, record.id, principal)
    except (VehicleRefused, CommandTimedOut) as error:  # offline: the switch fails anyway
        return [unreadable(error.message)], 0
    if (empty := nothing_to_fly(items)) is not None:
        return [empty], 0
    check = await asyncio.to_thread(hub.safety.check_mission, record, items)
    return list(check.violations), len(items)


async def check_current_item(
    hub: MissionServices, record: VehicleRecord, command: Command, principal: Principal
) -> None:
    """Refuse at once a current item beyond the mission, naming its length.

    The vehicle's MISSION_CURRENT.total is trusted to let an item through; an item beyond
    it (or an unknown total) is confirmed against the mission on board first, since the
    total trails a fresh upload by up to a telemetry period."""
    if not isinstance(command, MissionSetCurrentCommand):
        return
    total = record.state.mission_total if record.state else None
    if current_item_trusted(command.seq, total):
        return
    items = await on_board_mission(hub, record.id, principal)
    problem = current_item_problem(command.seq, len(items))
    if problem is not None:
        raise InvalidRequest("seq", problem)
