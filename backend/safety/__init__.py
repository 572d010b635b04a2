"""Safety rails: pure checks of commands against site and vehicle limits, and the parts
the mission rails (`backend.missions`) share with them.

No I/O here; the API and storage layers call these and turn violations into refusals.
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
from backend.safety.rails import SafetyRails
from backend.safety.snapshot import VehicleSnapshot
from backend.safety.violations import RULES, RuleName, Violation
from common.geodesy import GeoPoint, LocalFrame, haversine_m

__all__ = [
    "MAX_POLYGON_RADIUS_M",
    "MAX_POLYGON_VERTICES",
    "RULES",
    "FencePolygon",
    "GeoPoint",
    "Geofence",
    "InvalidGeofence",
    "LocalFrame",
    "RuleName",
    "SafetyRails",
    "VehicleSnapshot",
    "Violation",
    "check_arm",
    "check_goto",
    "check_set_home",
    "check_takeoff",
    "distance_to_boundary",
    "haversine_m",
    "point_in_polygon",
    "segment_leaves_polygon",
    "segment_relation",
    "validate_polygon",
]
