"""What a broken rule looks like: the rules' stable names, the violation, and the report a
check collects them in.

Each check returns every violated rule, not just the first, so an operator can fix a plan
in one go. When a rule needs something about the vehicle that is not known (its position,
home, altitude or battery level) the check fails closed with one "position_unknown"
violation naming what is missing and which rules it stopped.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Final, Literal

RuleName = Literal[
    "geofence",
    "geofence_max_altitude",
    "max_altitude",
    "min_altitude",
    "min_height_above_home",
    "max_distance_from_home",
    "min_launch_battery",
    "battery_sufficiency",
    "home_altitude",
    "position_unknown",
    "mission_item",
    "mission_unchecked",
    "survey_camera",
]
GEOFENCE: Final = "geofence"
GEOFENCE_MAX_ALTITUDE: Final = "geofence_max_altitude"
MAX_ALTITUDE: Final = "max_altitude"
MIN_ALTITUDE: Final = "min_altitude"
# A mission's navigation item (not a landing) too low above home, or below it.
MIN_HEIGHT_ABOVE_HOME: Final = "min_height_above_home"
MAX_DISTANCE_FROM_HOME: Final = "max_distance_from_home"
MIN_LAUNCH_BATTERY: Final = "min_launch_battery"
BATTERY_SUFFICIENCY: Final = "battery_sufficiency"
HOME_ALTITUDE: Final = "home_altitude"
POSITION_UNKNOWN: Final = "position_unknown"
# What an item's MAV_CMD needs (a place for a waypoint, a global frame, ...).
MISSION_ITEM: Final = "mission_item"
# A mission that would fly without having been checked: none on board, or unreadable.
MISSION_UNCHECKED: Final = "mission_unchecked"
# A survey planned for another camera than the one a chosen drone carries.
SURVEY_CAMERA: Final = "survey_camera"
RULES: Final[tuple[RuleName, ...]] = (
    GEOFENCE,
    GEOFENCE_MAX_ALTITUDE,
    MAX_ALTITUDE,
    MIN_ALTITUDE,
    MIN_HEIGHT_ABOVE_HOME,
    MAX_DISTANCE_FROM_HOME,
    MIN_LAUNCH_BATTERY,
    BATTERY_SUFFICIENCY,
    HOME_ALTITUDE,
    POSITION_UNKNOWN,
    MISSION_ITEM,
    MISSION_UNCHECKED,
    SURVEY_CAMERA,
)


@dataclass(frozen=True)
class Violation:
    rule: str
    message: str
    limit: float | None = None
    value: float | None = None
    # The mission items at fault (1 is the first after home), so that an editor can show
    # the refusal on them; empty for a rule about the vehicle or a command.
    items: tuple[int, ...] = ()


class Report:
    """Collects violations, and the unknowns that stopped rules from being checked."""

    _ITEM_ORDER = ("position", "home position", "home altitude", "altitude", "battery level")

    def __init__(self) -> None:
        self._violations: list[Violation] = []
        self._missing: dict[str, None] = {}
        self._blocked: dict[str, None] = {}

    def add(
        self,
        rule: str,
        message: str,
        limit: float | None,
        value: float | None,
        items: Sequence[int | None] = (),
    ) -> None:
        at_fault = tuple(dict.fromkeys(item for item in items if item is not None))
        self._violations.append(Violation(rule, message, limit, value, at_fault))

    def unknown(self, item: str, rule: str) -> None:
        self._missing[item] = None
        self._blocked[rule] = None

    def violations(self) -> list[Violation]:
        result = list(self._violations)
        if self._missing:
            items = [i for i in self._ITEM_ORDER if i in self._missing]
            verb = "is" if len(items) == 1 else "are"
            rules = [r for r in RULES if r in self._blocked]
            result.append(
                Violation(
                    POSITION_UNKNOWN,
                    f"cannot check {and_join(rules)}: the vehicle's {and_join(items)} {verb} "
                    "not known",
                )
            )
        return result


# --- Wording shared by the messages ----------------------------------------------------------


def pair(value: float, limit: float, decimals: int) -> tuple[str, str]:
    """Format a value and its limit so that they never print the same when they differ."""
    while True:
        shown, bound = f"{value:.{decimals}f}", f"{limit:.{decimals}f}"
        if shown != bound or decimals >= 3:
            return shown, bound
        decimals += 1


def others(count: int, noun: str) -> str:
    return "" if count <= 1 else f" ({count} {noun})"


def and_join(words: Sequence[str]) -> str:
    return words[0] if len(words) == 1 else ", ".join(words[:-1]) + " and " + words[-1]


def count(n: int, noun: str) -> str:
    return f"{n} {noun}" if n == 1 else f"{n} {noun}s"
