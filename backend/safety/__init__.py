"""Safety: every rule that can refuse a command, a mission, a parameter write or a
formation, the rails they are checked against, where those are stored, and their routes.

The rules are pure (no I/O, no HTTP, no storage) and exported here:

- `rails`: the limits (a site's, a vehicle's own laid over them); `violations`: rule
  names and the report; `snapshot`: what is known of the vehicle; `limits`: one value
  against one limit; `geometry` and `geofence`: the fence polygon and its tests.
- `commands`: arm, take-off, go-to and a new home against the rails.
- `mission_waypoints`, `mission_battery`, `mission_rails`, `mission_check`: a mission's
  places, the battery it needs, every place and leg against the rails, and the mission
  check (item rules, then the rails); `mission_on_board`: the AUTO gate.
- `critical_params`: the parameters only an admin may change.
- `schemas`, `mission_schemas`: the REST bodies (rails, violations, a mission, its check).

Around them, with I/O, imported by their own paths (so that importing a rule loads no
database or web framework): `rails_store` (the stored rails), `service` (`SafetyService`,
the entry points the fleet, the surveys and the formations call), `dependencies` and
`routes` (the REST routes).
"""

from backend.safety.commands import check_arm, check_goto, check_set_home, check_takeoff
from backend.safety.geofence import Geofence
from backend.safety.geometry import (
    MAX_POLYGON_RADIUS_M,
    MAX_POLYGON_VERTICES,
    FencePolygon,
    InvalidGeofence,
    distance_to_boundary,
    point_in_polygon,
    segment_leaves_polygon,
    segment_relation,
    validate_polygon,
)
from backend.safety.mission_battery import BatteryEstimate, BatteryModel, estimate_plan
from backend.safety.mission_check import check_mission
from backend.safety.mission_rails import PlanCheck, check_plan, evaluate_plan
from backend.safety.mission_waypoints import Waypoint, mission_waypoints
from backend.safety.rails import SafetyRails
from backend.safety.snapshot import VehicleSnapshot
from backend.safety.violations import RULES, RuleName, Violation
from common.geodesy import GeoPoint, LocalFrame, haversine_m

__all__ = [
    "MAX_POLYGON_RADIUS_M",
    "MAX_POLYGON_VERTICES",
    "RULES",
    "BatteryEstimate",
    "BatteryModel",
    "FencePolygon",
    "GeoPoint",
    "Geofence",
    "InvalidGeofence",
    "LocalFrame",
    "PlanCheck",
    "RuleName",
    "SafetyRails",
    "VehicleSnapshot",
    "Violation",
    "Waypoint",
    "check_arm",
    "check_goto",
    "check_mission",
    "check_plan",
    "check_set_home",
    "check_takeoff",
    "distance_to_boundary",
    "estimate_plan",
    "evaluate_plan",
    "haversine_m",
    "mission_waypoints",
    "point_in_polygon",
    "segment_leaves_polygon",
    "segment_relation",
    "validate_polygon",
]
