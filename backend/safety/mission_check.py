"""The mission check, the same for a check, an upload and a switch to AUTO: what each
item's command needs, then every rail the mission's places break, and the battery
estimate when it can be made."""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Sequence

from backend.safety.mission_rails import PlanCheck, evaluate_plan
from backend.safety.mission_waypoints import mission_waypoints
from backend.safety.rails import SafetyRails
from backend.safety.snapshot import VehicleSnapshot
from backend.safety.violations import MISSION_ITEM, Violation
from protocol.messages import MissionItem
from protocol.mission_rules import GROUND_VEHICLES, mission_problems_by_item


def check_mission(
    items: Sequence[MissionItem],
    vehicle: VehicleSnapshot,
    rails: Callable[[], SafetyRails],
    vehicle_type: str,
    autopilot: str,
) -> PlanCheck:
    """Items number from 1 (home is 0). ``rails`` gives the vehicle's effective rails; it
    is read only when the mission goes somewhere (a mission of settings alone needs none).
    Raises InvalidRequest when an item's altitude cannot be put above home."""
    problems = tuple(
        Violation(MISSION_ITEM, problem, items=(number,))
        for number, problem in mission_problems_by_item(items, vehicle_type, autopilot)
    )
    waypoints = mission_waypoints(items, vehicle, autopilot)
    if not waypoints:
        return PlanCheck(problems, None)  # no place to go: nothing for the rails
    limits = rails()
    if vehicle_type in GROUND_VEHICLES:
        # A rover's or a boat's altitude is where the ground or water is, a submarine's
        # below it: no height above home to keep.
        limits = dataclasses.replace(limits, min_height_above_home_m=None)
    plan = evaluate_plan(limits, vehicle, waypoints)
    return PlanCheck(problems + plan.violations, plan.estimate)
