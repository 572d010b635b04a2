"""Missions on the hub: the mission model, its item rules, its rails, and the AUTO gate's
check. Pure domain logic: no HTTP, no I/O (the fleet services read and write missions on
vehicles; the API routes are thin on top).

- `schemas`: the REST bodies (a mission, the mission check's answer).
- `waypoints`: the places a mission's items take the vehicle.
- `battery`: the battery a mission needs, home again and landed.
- `rails`: every waypoint and leg against the safety rails.
- `check`: the mission check: item rules (`protocol.mission_rules`, shared with the
  agent), then the rails.
- `gate`: what a switch to AUTO and a new current item must pass.

Planners (survey, formation) produce `MissionItem` lists and land in subpackages here.
"""

from backend.missions.battery import BatteryEstimate, BatteryModel, estimate_plan
from backend.missions.check import check_mission
from backend.missions.rails import PlanCheck, check_plan, evaluate_plan
from backend.missions.waypoints import Waypoint, mission_waypoints
from protocol.mission_rules import item_problems, mission_problems

__all__ = [
    "BatteryEstimate",
    "BatteryModel",
    "PlanCheck",
    "Waypoint",
    "check_mission",
    "check_plan",
    "estimate_plan",
    "evaluate_plan",
    "item_problems",
    "mission_problems",
    "mission_waypoints",
]
