"""REST bodies for safety rails and their violations, with conversions to the rails'
dataclasses (the mission bodies are `mission_schemas`).

Unknown fields are rejected: a misspelt limit that was silently ignored would leave a vehicle
without the rail its operator thinks it has. NaN and infinities are rejected for the same
reason (they compare false against every limit).
"""

from __future__ import annotations

from typing import Self

from pydantic import BaseModel, ConfigDict, Field, field_validator, model_validator

from backend.safety.geofence import Geofence
from backend.safety.geometry import MAX_POLYGON_VERTICES, validate_polygon
from backend.safety.rails import (
    DEFAULT_BATTERY_RESERVE_PCT,
    DEFAULT_MIN_HEIGHT_ABOVE_HOME_M,
    SafetyRails,
)
from backend.safety.violations import RuleName, Violation
from common.geodesy import GeoPoint
from protocol.messages import Number

MAX_ALTITUDE_M = 10_000.0
MAX_DISTANCE_M = 1_000_000.0


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", allow_inf_nan=False)


class GeoPointModel(_Strict):
    lat: Number = Field(ge=-90, le=90, description="Latitude, degrees north (WGS84)")
    lon: Number = Field(ge=-180, le=180, description="Longitude, degrees east (WGS84)")


class GeofenceModel(_Strict):
    # Named objects rather than [lat, lon] pairs: GeoJSON orders pairs [lon, lat], and a
    # swapped pair still looks like a valid fence somewhere else on Earth.
    polygon: list[GeoPointModel] = Field(
        max_length=MAX_POLYGON_VERTICES + 1,
        description=(
            'Vertices in order, each {"lat": .., "lon": ..}; the polygon closes itself '
            "(repeating the first vertex at the end is allowed). At least 3 distinct vertices, "
            f"at most {MAX_POLYGON_VERTICES}, no crossing edges, within 100 km of its centre."
        ),
    )
    max_altitude_m: Number | None = Field(
        default=None,
        ge=0,
        le=MAX_ALTITUDE_M,
        description="Ceiling inside the fence, metres above home; null for none",
    )

    @field_validator("polygon")
    @classmethod
    def _polygon_is_a_fence(cls, polygon: list[GeoPointModel]) -> list[GeoPointModel]:
        # InvalidGeofence is a ValueError, so pydantic reports its message against `polygon`.
        vertices = validate_polygon([(p.lat, p.lon) for p in polygon])
        return [GeoPointModel(lat=lat, lon=lon) for lat, lon in vertices]

    def to_geofence(self) -> Geofence:
        return Geofence(
            polygon=tuple(GeoPoint(p.lat, p.lon) for p in self.polygon),
            max_altitude_m=self.max_altitude_m,
        )

    @classmethod
    def from_geofence(cls, fence: Geofence) -> GeofenceModel:
        return cls(
            polygon=[GeoPointModel(lat=p.lat, lon=p.lon) for p in fence.polygon],
            max_altitude_m=fence.max_altitude_m,
        )


class SafetyRailsModel(_Strict):
    """Site-wide rails, or one vehicle's overrides (null fields fall back to the site's)."""

    geofence: GeofenceModel | None = Field(default=None, description="Null for no geofence")
    max_distance_from_home_m: Number | None = Field(
        default=None, gt=0, le=MAX_DISTANCE_M, description="Horizontal range limit, metres"
    )
    min_altitude_m: Number | None = Field(
        default=None, ge=0, le=MAX_ALTITUDE_M, description="Floor for targets, metres above home"
    )
    max_altitude_m: Number | None = Field(
        default=None, ge=0, le=MAX_ALTITUDE_M, description="Ceiling, metres above home"
    )
    min_launch_battery_pct: Number | None = Field(
        default=None, ge=0, le=100, description="Battery needed to arm or take off, percent"
    )
    battery_reserve_pct: Number = Field(
        default=DEFAULT_BATTERY_RESERVE_PCT,
        ge=0,
        le=100,
        description="Battery that must remain after a planned mission and its return home",
    )
    min_height_above_home_m: Number | None = Field(
        default=DEFAULT_MIN_HEIGHT_ABOVE_HOME_M,
        ge=0,
        le=MAX_ALTITUDE_M,
        description="Lowest a mission's navigation items (but its landings) may go, metres "
        "above home; an item above terrain counts its height above terrain as above home. "
        "Null: no such rule (a site's rails only; a vehicle's null keeps the site's)",
    )

    @model_validator(mode="after")
    def _floor_below_ceiling(self) -> Self:
        floor, ceiling = self.min_altitude_m, self.max_altitude_m
        if floor is not None and ceiling is not None and floor > ceiling:
            raise ValueError(
                f"min_altitude_m {floor} m is above max_altitude_m {ceiling} m; "
                "no altitude could pass"
            )
        return self

    def to_rails(self) -> SafetyRails:
        return SafetyRails(
            geofence=self.geofence.to_geofence() if self.geofence else None,
            max_distance_from_home_m=self.max_distance_from_home_m,
            min_altitude_m=self.min_altitude_m,
            max_altitude_m=self.max_altitude_m,
            min_launch_battery_pct=self.min_launch_battery_pct,
            battery_reserve_pct=self.battery_reserve_pct,
            min_height_above_home_m=self.min_height_above_home_m,
        )

    @classmethod
    def from_rails(cls, rails: SafetyRails) -> SafetyRailsModel:
        return cls(
            geofence=GeofenceModel.from_geofence(rails.geofence) if rails.geofence else None,
            max_distance_from_home_m=rails.max_distance_from_home_m,
            min_altitude_m=rails.min_altitude_m,
            max_altitude_m=rails.max_altitude_m,
            min_launch_battery_pct=rails.min_launch_battery_pct,
            battery_reserve_pct=rails.battery_reserve_pct,
            min_height_above_home_m=rails.min_height_above_home_m,
        )


class ViolationModel(_Strict):
    rule: RuleName = Field(description="Stable name of the rule that was broken")
    message: str = Field(description="What is wrong, with the numbers and units")
    limit: float | None = Field(default=None, description="The rule's limit, where it has one")
    value: float | None = Field(default=None, description="The offending value, where it has one")
    items: list[int] = Field(
        default_factory=list,
        description="The mission items at fault (1 is the first after home; a leg is listed "
        "by the item it flies to); empty for a rule about the vehicle or a command",
    )

    @classmethod
    def from_violation(cls, violation: Violation) -> ViolationModel:
        return cls.model_validate(
            {
                "rule": violation.rule,
                "message": violation.message,
                "limit": violation.limit,
                "value": violation.value,
                "items": list(violation.items),
            }
        )
