"""The geofence: a polygon the vehicle must stay inside, and the checks of a place, and of
the straight leg to it, against that polygon."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from backend.safety.geometry import FencePolygon, InvalidGeofence
from backend.safety.violations import GEOFENCE, Report
from common.geodesy import GeoPoint


@dataclass(frozen=True)
class Geofence:
    """A polygon the vehicle must stay inside, optionally with a ceiling above home.

    Validated on construction (raises InvalidGeofence). A repeated closing vertex is dropped
    from `polygon`.
    """

    polygon: tuple[GeoPoint, ...]
    max_altitude_m: float | None = None
    _shape: FencePolygon = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        shape = FencePolygon([(p.lat, p.lon) for p in self.polygon])
        alt = self.max_altitude_m
        if alt is not None and not (math.isfinite(alt) and alt >= 0):
            raise InvalidGeofence(f"max_altitude_m {alt} must be a finite number of metres ≥ 0")
        object.__setattr__(
            self, "polygon", tuple(GeoPoint(lat, lon) for lat, lon in shape.vertices)
        )
        object.__setattr__(self, "_shape", shape)

    def contains(self, point: GeoPoint) -> bool:
        return self._shape.contains(point.lat, point.lon)

    def distance_outside_m(self, point: GeoPoint) -> float:
        return self._shape.distance_outside_m(point.lat, point.lon)

    def leg_leaves(self, start: GeoPoint, end: GeoPoint) -> bool:
        return self._shape.leg_leaves(start.lat, start.lon, end.lat, end.lon)


def outside_message(label: str, distance: float) -> str:
    return f"{label} is {distance:.0f} m outside the geofence"


def check_inside(fence: Geofence, here: GeoPoint | None, label: str, report: Report) -> None:
    """The vehicle itself (``here``, None when unknown) must be inside the fence."""
    if here is None:
        report.unknown("position", GEOFENCE)
    elif not fence.contains(here):
        outside = fence.distance_outside_m(here)
        report.add(GEOFENCE, outside_message(label, outside), None, outside)


def check_way_to(
    fence: Geofence,
    here: GeoPoint | None,
    target: GeoPoint | None,
    report: Report,
    *,
    label: str,
    leg_label: str,
    consequence: str = "",
) -> None:
    """A place to fly to (None when unknown) must be inside the fence, and so must the
    straight leg to it from the vehicle (``here``, None when unknown). A vehicle already
    outside is not held to the leg: refusing the way back in would leave no way to recover
    it. ``consequence`` ends each message (why the place matters)."""
    if target is None:
        report.unknown("position", GEOFENCE)
    elif not fence.contains(target):
        outside = fence.distance_outside_m(target)
        message = outside_message(label, outside) + (
            f": {consequence} there" if consequence else ""
        )
        report.add(GEOFENCE, message, None, outside)
    elif here is None:
        report.unknown("position", GEOFENCE)
    elif fence.contains(here) and fence.leg_leaves(here, target):
        report.add(
            GEOFENCE,
            f"the straight leg from the vehicle's position to {leg_label} leaves the geofence"
            + (f": {consequence} it" if consequence else ""),
            None,
            None,
        )
