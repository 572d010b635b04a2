"""The safety rails themselves: the limits every command and mission is checked against
(a site's, and a vehicle's own laid over them). The checks live beside this module, one
job each: `violations` (rule names and the report), `snapshot` (what is known of the
vehicle), `limits` (one value against one limit), `geofence`, and `commands` (the command
rails); the mission rails are the missions module's (`backend.missions.rails`).

Altitudes are metres above home.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields
from typing import Final, TypeVar

from backend.safety.geofence import Geofence

DEFAULT_BATTERY_RESERVE_PCT: Final = 20.0

_T = TypeVar("_T")


@dataclass(frozen=True)
class SafetyRails:
    geofence: Geofence | None = None
    max_distance_from_home_m: float | None = None
    min_altitude_m: float | None = None
    max_altitude_m: float | None = None
    min_launch_battery_pct: float | None = None
    battery_reserve_pct: float = DEFAULT_BATTERY_RESERVE_PCT

    def __post_init__(self) -> None:
        # A NaN limit would let everything through, so bad limits are a hard error.
        for f in fields(self):
            value = getattr(self, f.name)
            if isinstance(value, float | int) and not (math.isfinite(value) and value >= 0):
                raise ValueError(f"{f.name} {value} must be a finite number ≥ 0")
        for name in ("min_launch_battery_pct", "battery_reserve_pct"):
            pct = getattr(self, name)
            if pct is not None and pct > 100:
                raise ValueError(f"{name} {pct} must be at most 100")

    def merged_with(self, override: SafetyRails | None) -> SafetyRails:
        """Site rails with a vehicle's own values laid over them wherever it sets one.

        The reserve has no "unset" value, so a vehicle's reserve counts as set when it
        differs from the default; a vehicle cannot override a site's reserve back to
        exactly the default.
        """
        if override is None:
            return self
        reserve = override.battery_reserve_pct
        return SafetyRails(
            geofence=_prefer(override.geofence, self.geofence),
            max_distance_from_home_m=_prefer(
                override.max_distance_from_home_m, self.max_distance_from_home_m
            ),
            min_altitude_m=_prefer(override.min_altitude_m, self.min_altitude_m),
            max_altitude_m=_prefer(override.max_altitude_m, self.max_altitude_m),
            min_launch_battery_pct=_prefer(
                override.min_launch_battery_pct, self.min_launch_battery_pct
            ),
            battery_reserve_pct=(
                self.battery_reserve_pct if reserve == DEFAULT_BATTERY_RESERVE_PCT else reserve
            ),
        )


def _prefer(own: _T | None, site: _T | None) -> _T | None:
    return site if own is None else own
