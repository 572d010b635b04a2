"""The formation feature: a leader (a vehicle, or a virtual leader that is only a moving
point) flies a route, and followers hold offsets from it.

- `schemas`: the REST body of a formation and its plan.
- `route`: the leader's route in time: legs at a speed, a pause at each waypoint.
- `planner`: the checks (separation of every slot, roles, speed, the rails with every
  slot around the route) and the plan the hub hands to the followers' agents.
- `service`: formations in flight (start, change, stop, stored in `store`); `active`
  holds one, `slots` what each member is told of its place, `relay` the leader's state
  and scans (`leader_scans`) to the followers, `metrics` how well each keeps its slot.
- `routes` (through `deps`), `scene_layer` (the 3D view), and `wiring`, which app.py
  calls to put the feature on a started hub.

The geometry the agents share (offsets, presets, prediction) is `common.formation`.
"""

from backend.formation.planner import FormationPlan, FormationRefused, plan_formation
from backend.formation.route import LeaderRoute

__all__ = ["FormationPlan", "FormationRefused", "LeaderRoute", "plan_formation"]
