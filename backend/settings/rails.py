"""The site's safety rails: the altitudes, distance and batteries that a command or a
mission must keep to."""

from __future__ import annotations

from pydantic import BaseModel, Field


class SafetyRailSettings(BaseModel):
    """The site's defaults for every vehicle's safety rails."""

    max_altitude_m: float | None = Field(default=120.0, description="site ceiling above home")
    min_altitude_m: float | None = Field(default=None, description="site floor for targets")
    max_distance_from_home_m: float | None = Field(default=2000.0)
    min_launch_battery_pct: float | None = Field(default=30.0)
    battery_reserve_pct: float = Field(default=20.0, ge=0, le=100)
    min_height_above_home_m: float | None = Field(
        default=2.0, ge=0, description="lowest a mission's navigation items go but landings"
    )
