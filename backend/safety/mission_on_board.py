"""The AUTO gate: a switch to the mission mode flies only a mission that passed the
mission check, and a new current item must be one of the mission's.

Both read the vehicle's own mission (a download), not the hub's memory of what it sent:
another GCS may have loaded a different one. The download is the fleet's (its
dispatcher); it is handed in as a ``MissionReader``, so these rules do no I/O of their own.
"""

from __future__ import annotations

import asyncio
from collections.abc import Awaitable, Callable

from backend.errors import CommandTimedOut, InvalidRequest, VehicleRefused
from backend.safety.mission_rails import PlanCheck
from backend.safety.violations import MISSION_UNCHECKED, Violation
from protocol.messages import Command, MissionItem, MissionSetCurrentCommand, SetModeCommand
from protocol.mission_rules import MISSION_MODES

# The vehicle's mission now, without home (item 1 first). Raises GcsError when it cannot
# be read (VehicleRefused, or the dispatcher's own errors).
MissionReader = Callable[[], Awaitable[list[MissionItem]]]


def starts_mission(command: Command) -> bool:
    return isinstance(command, SetModeCommand) and command.mode.upper() in MISSION_MODES


def unreadable(reason: str) -> Violation:
    """The mission on board could not be read, so it cannot have been checked."""
    return Violation(
        MISSION_UNCHECKED, f"the mission on board could not be read to check it: {reason}"
    )


def nothing_to_fly(items: list[MissionItem]) -> Violation | None:
    return (
        Violation(MISSION_UNCHECKED, "the vehicle holds no mission to fly") if not items else None
    )


def current_item_trusted(seq: int, total: int | None) -> bool:
    """An item within the vehicle's own MISSION_CURRENT.total is let through without a
    download; beyond it (or with no total) the mission on board decides, since the total
    trails a fresh upload by up to a telemetry period."""
    return total is not None and seq <= total


def current_item_problem(seq: int, count: int) -> str | None:
    """Why item ``seq`` cannot be the current one of a mission of ``count`` items."""
    if seq <= count:
        return None
    held = f"it has {count} items (1..{count})" if count else "it holds no mission"
    return f"item {seq} is not in the mission: {held}"


async def unchecked_mission(
    read: MissionReader, check: Callable[[list[MissionItem]], PlanCheck]
) -> tuple[list[Violation], int]:
    """Every problem of the mission on board (``check``: the mission check, as for an
    upload, run off the event loop), and its number of items; a mission that cannot be
    read or is empty is a violation too."""
    try:
        items = await read()
    except (VehicleRefused, CommandTimedOut) as error:  # offline: the switch fails anyway
        return [unreadable(error.message)], 0
    if (empty := nothing_to_fly(items)) is not None:
        return [empty], 0
    plan = await asyncio.to_thread(check, items)
    return list(plan.violations), len(items)


async def check_current_item(read: MissionReader, total: int | None, command: Command) -> None:
    """Refuse at once a current item beyond the mission, naming its length.

    The vehicle's MISSION_CURRENT.total (``total``) is trusted to let an item through; an
    item beyond it (or an unknown total) is confirmed against the mission on board first,
    since the total trails a fresh upload by up to a telemetry period."""
    if not isinstance(command, MissionSetCurrentCommand):
        return
    if current_item_trusted(command.seq, total):
        return
    problem = current_item_problem(command.seq, len(await read()))
    if problem is not None:
        raise InvalidRequest("seq", problem)
