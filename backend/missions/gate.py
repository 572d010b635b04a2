"""The AUTO gate's rules: a switch to the mission mode flies only a mission that passed
the mission check, and a new current item must be one of the mission's. The hub reads the
vehicle's own mission for them (`backend.fleet.mission_gate`); the rules are here."""

from __future__ import annotations

from backend.safety.violations import MISSION_UNCHECKED, Violation
from protocol.messages import Command, MissionItem, SetModeCommand
from protocol.mission_rules import MISSION_MODES


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
