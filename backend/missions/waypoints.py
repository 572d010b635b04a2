"""The places a mission takes the vehicle, read from its items for the rails to check."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from backend.errors import InvalidRequest
from backend.safety.snapshot import VehicleSnapshot
from protocol.messages import MissionItem

# The commands that fly to (or act at) their item's position. A take-off is not among
# them: it climbs where the vehicle stands.
FLIES_TO = frozenset(
    {
        mavlink2.MAV_CMD_NAV_WAYPOINT,
        mavlink2.MAV_CMD_NAV_LOITER_UNLIM,
        mavlink2.MAV_CMD_NAV_LOITER_TURNS,
        mavlink2.MAV_CMD_NAV_LOITER_TIME,
        mavlink2.MAV_CMD_NAV_LAND,
        mavlink2.MAV_CMD_NAV_SPLINE_WAYPOINT,
        mavlink2.MAV_CMD_NAV_LOITER_TO_ALT,
        mavlink2.MAV_CMD_NAV_VTOL_TAKEOFF,
        mavlink2.MAV_CMD_NAV_VTOL_LAND,
        mavlink2.MAV_CMD_NAV_PAYLOAD_PLACE,
        # With a position, home moves there mid-mission, so RTL goes there.
        mavlink2.MAV_CMD_DO_SET_HOME,
    }
)
# Frames whose altitude is above mean sea level rather than above home.
AMSL_FRAMES = frozenset({mavlink2.MAV_FRAME_GLOBAL, mavlink2.MAV_FRAME_GLOBAL_INT})


@dataclass(frozen=True)
class Waypoint:
    lat: float
    lon: float
    alt_rel: float
    # The mission item this place comes from (1 is the first after home), so that a
    # refusal names the item the operator wrote; None: named by its place in the list.
    item: int | None = None

    def name(self, index: int) -> str:
        """``index`` counts from 1 among the waypoints."""
        return f"item {self.item}" if self.item is not None else f"waypoint {index}"


def mission_waypoints(items: Sequence[MissionItem], vehicle: VehicleSnapshot) -> list[Waypoint]:
    """The places a mission will take the vehicle, altitudes above home.

    A take-off climbs where the vehicle stands; a land with no position lands in place.
    Raises InvalidRequest for an altitude above sea level when home's is not known."""
    home_alt = vehicle.home_alt_msl
    points: list[Waypoint] = []
    for number, item in enumerate(items, 1):
        has_position = (item.lat, item.lon) != (0.0, 0.0)
        alt = item.alt
        if item.frame in AMSL_FRAMES:
            if home_alt is None:
                # The rails measure from home: refuse rather than guess.
                raise InvalidRequest(
                    "items",
                    f"item {number}: its altitude is above sea level, and the vehicle has "
                    "not reported home's altitude to check it against",
                )
            alt = item.alt - home_alt
        if item.command in FLIES_TO and has_position:
            points.append(Waypoint(item.lat, item.lon, alt, number))
        elif (
            item.command == mavlink2.MAV_CMD_NAV_TAKEOFF
            and vehicle.lat is not None
            and vehicle.lon is not None
        ):
            points.append(Waypoint(vehicle.lat, vehicle.lon, item.alt, number))
    return points
