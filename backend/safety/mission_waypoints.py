"""The places a mission takes the vehicle, read from its items for the rails to check."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Literal

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from backend.errors import InvalidRequest
from backend.safety.snapshot import VehicleSnapshot
from protocol.messages import MissionItem

# The commands that fly to (or act at) their item's position. A take-off is not among
# them on ArduPilot, which climbs where the vehicle stands (see mission_waypoints).
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
# The items that go down to the ground on purpose: the minimum height above home is not
# theirs to keep. DO_SET_HOME is not a place flown at its altitude (it is home's own).
_NOT_HELD_ABOVE_HOME = frozenset(
    {mavlink2.MAV_CMD_NAV_LAND, mavlink2.MAV_CMD_NAV_VTOL_LAND, mavlink2.MAV_CMD_DO_SET_HOME}
)
# Frames whose altitude is above mean sea level rather than above home.
AMSL_FRAMES = frozenset({mavlink2.MAV_FRAME_GLOBAL, mavlink2.MAV_FRAME_GLOBAL_INT})
# Frames whose altitude is above the terrain under the item. The hub has no terrain model,
# so such an altitude is taken as above home (exact over flat ground) and said so.
TERRAIN_FRAMES = frozenset(
    {mavlink2.MAV_FRAME_GLOBAL_TERRAIN_ALT, mavlink2.MAV_FRAME_GLOBAL_TERRAIN_ALT_INT}
)

Datum = Literal["home", "sea level", "terrain"]


@dataclass(frozen=True)
class Waypoint:
    lat: float
    lon: float
    alt_rel: float
    # The mission item this place comes from (1 is the first after home), so that a
    # refusal names the item the operator wrote; None: named by its place in the list.
    item: int | None = None
    # What the item's altitude was written above, and that altitude as written, so that a
    # refusal can say it in the operator's terms.
    datum: Datum = "home"
    alt_written: float | None = None
    # Held to the minimum height above home: every navigation place but a landing's.
    held_above_home: bool = True

    def name(self, index: int) -> str:
        """``index`` counts from 1 among the waypoints."""
        return f"item {self.item}" if self.item is not None else f"waypoint {index}"


def _datum(frame: int) -> Datum:
    if frame in AMSL_FRAMES:
        return "sea level"
    return "terrain" if frame in TERRAIN_FRAMES else "home"


def mission_waypoints(
    items: Sequence[MissionItem], vehicle: VehicleSnapshot, autopilot: str = "ardupilot"
) -> list[Waypoint]:
    """The places a mission will take the vehicle, altitudes above home, as the vehicle's
    autopilot reads its items.

    ArduPilot reads a positioned item at 0, 0 as "here" and climbs a take-off where the
    vehicle stands, whatever the item's latitude and longitude. PX4 flies to every
    position as written: a take-off climbs, then flies to the take-off item's position
    (and to 0°N 0°E if that is what it says), so on PX4 each position is a place.
    Raises InvalidRequest for an altitude above sea level when home's is not known."""
    home_alt = vehicle.home_alt_msl
    literal = autopilot == "px4"
    points: list[Waypoint] = []
    for number, item in enumerate(items, 1):
        # DO_SET_HOME at 0, 0 is "use the current position" (param1 1) on either.
        has_position = (item.lat, item.lon) != (0.0, 0.0) or (
            literal and item.command != mavlink2.MAV_CMD_DO_SET_HOME
        )
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
        takeoff = item.command == mavlink2.MAV_CMD_NAV_TAKEOFF
        where: tuple[float, float] | None = None
        if (item.command in FLIES_TO or (takeoff and literal)) and has_position:
            where = (item.lat, item.lon)
        elif takeoff and vehicle.lat is not None and vehicle.lon is not None:
            where = (vehicle.lat, vehicle.lon)
        if where is not None:
            points.append(
                Waypoint(
                    *where,
                    alt,
                    number,
                    datum=_datum(item.frame),
                    alt_written=item.alt,
                    held_above_home=item.command not in _NOT_HELD_ABOVE_HOME,
                )
            )
    return points
