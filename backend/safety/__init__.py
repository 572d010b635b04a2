"""Safety rails: pure checks of commands and missions against site and vehicle limits.

No I/O here; the API and storage layers call these and turn violations into refusals.
"""

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
from backend.safety.rails import (
    RULES,
    BatteryEstimate,
    BatteryModel,
    Geofence,
    PlanCheck,
    RuleName,
    SafetyRails,
    VehicleSnapshot,
    Violation,
    Waypoint,
    check_arm,
    check_goto,
    check_plan,
    check_set_home,
    check_takeoff,
    estimate_plan,
    evaluate_plan,
)
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
    "check_plan",
    "check_set_home",
    "check_takeoff",
    "distance_to_boundary",
    "estimate_plan",
    "evaluate_plan",
    "haversine_m",
    "point_in_polygon",
    "segment_leaves_polygon",
    "segment_relation",
    "validate_polygon",
]
