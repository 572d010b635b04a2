"""The safety rails themselves: the limits every command and mission is checked against
(a site's, and a vehicle's own laid over them). The checks live beside this module, one
job each: `violations` (rule names and the report), `snapshot` (what is known of the
vehicle), `limits` (one value against one limit), `geofence`, and `commands` (the command
rails); and the mission rails, `mission_rails`.

Altitudes are metres above home.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields
from typing import Final, TypeVar

from backend.safety.geofence import Geofence

DEFAULT_BATTERY_RESERVE_PCT: Final = 20.0
# A mission's navigation items (but its landings) stay at least this far above home: a
# waypoint below home is a typing slip (a negative relative altitude, a sea-level altitude
# written as if above home) that flies the vehicle into the ground.
DEFAULT_MIN_HEIGHT_ABOVE_HOME_M: Final = 2.0

_T = TypeVar("_T")


@dataclass(frozen=True)
class SafetyRails:
    geofence: Geofence | None = None
    max_distance_from_home_m: float | None = None
    min_altitude_m: float | None = None
    max_altitude_m: float | None = None
    min_launch_battery_pct: float | None = None
    battery_reserve_pct: float = DEFAULT_BATTERY_RESERVE_PCT
    # None: no such rule (a site's choice); a vehicle's own value counts as set when it
    # differs from the default, as the reserve does.
    min_height_above_home_m: float | None = DEFAULT_MIN_HEIGHT_ABOVE_HOME_M

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

        The reserve and the minimum height above home have no "unset" value of their own
        (a vehicle's rails body that leaves them out carries the defaults), so a vehicle's
        counts as set when it differs from the default; a vehicle cannot override a site's
        back to exactly the default, nor switch the minimum height off (only a site can).
        """
        if override is None:
            return self
        reserve = override.battery_reserve_pct
        height = override.min_height_above_home_m
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
            min_height_above_home_m=(
                self.min_height_above_home_m
                if height in (None, DEFAULT_MIN_HEIGHT_ABOVE_HOME_M)
                else height
            ),
        )


def _prefer(own: _T | None, site: _T | None) -> _T | None:
    return site if own is None else own
