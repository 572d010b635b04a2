"""Formation missions: a leader (a vehicle, or a virtual leader that is only a moving
point) flies a route, and followers hold offsets from it.

- `schemas`: the REST body of a formation and its plan.
- `route`: the leader's route in time: legs at a speed, a pause at each waypoint.
- `planner`: the checks (separation of every slot, roles, speed, the rails with every
  slot around the route) and the plan the hub hands to the followers' agents.

The geometry the agents share (offsets, presets, prediction) is `common.formation`.
"""

from backend.missions.formation.planner import FormationPlan, FormationRefused, plan_formation
from backend.missions.formation.route import LeaderRoute

__all__ = ["FormationPlan", "FormationRefused", "LeaderRoute", "plan_formation"]
