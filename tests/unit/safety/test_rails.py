"""The rails themselves: a vehicle's laid over the site's, limits that must be numbers,
the fence validated, the rule names stable."""

from __future__ import annotations

import math

import pytest

from backend.safety import RULES, Geofence, InvalidGeofence, SafetyRails
from tests.unit.safety.shapes import geo, u_fence

# --- Rails ----------------------------------------------------------------------------------


def test_merged_rails_take_vehicle_values_where_set() -> None:
    site = SafetyRails(
        geofence=u_fence(),
        max_distance_from_home_m=500,
        max_altitude_m=120,
        min_launch_battery_pct=30,
        battery_reserve_pct=25,
    )
    own_fence = Geofence((geo(0, 0), geo(10, 0), geo(0, 10)))
    merged = site.merged_with(SafetyRails(geofence=own_fence, max_altitude_m=60))
    assert merged == SafetyRails(
        geofence=own_fence,
        max_distance_from_home_m=500,
        max_altitude_m=60,
        min_launch_battery_pct=30,
        battery_reserve_pct=25,
    )
    assert site.merged_with(SafetyRails(battery_reserve_pct=35)).battery_reserve_pct == 35
    assert site.merged_with(None) is site
    assert SafetyRails().merged_with(SafetyRails(min_altitude_m=5)).min_altitude_m == 5


def test_rails_refuse_limits_that_would_pass_everything() -> None:
    with pytest.raises(ValueError, match="max_altitude_m nan"):
        SafetyRails(max_altitude_m=math.nan)
    with pytest.raises(ValueError, match="battery_reserve_pct 120"):
        SafetyRails(battery_reserve_pct=120)
    with pytest.raises(InvalidGeofence, match="max_altitude_m -1"):
        Geofence((geo(0, 0), geo(10, 0), geo(0, 10)), max_altitude_m=-1)


def test_geofence_validates_its_polygon() -> None:
    with pytest.raises(InvalidGeofence, match="edges 1 and 3 cross"):
        Geofence((geo(0, 0), geo(100, 100), geo(100, 0), geo(0, 100)))
    closed = Geofence((geo(0, 0), geo(10, 0), geo(0, 10), geo(0, 0)))
    assert len(closed.polygon) == 3
    assert closed == Geofence((geo(0, 0), geo(10, 0), geo(0, 10)))
    assert hash(closed) == hash(Geofence((geo(0, 0), geo(10, 0), geo(0, 10))))


def test_rule_names_are_stable() -> None:
    assert RULES == (
        "geofence",
        "geofence_max_altitude",
        "max_altitude",
        "min_altitude",
        "min_height_above_home",
        "max_distance_from_home",
        "min_launch_battery",
        "battery_sufficiency",
        "home_altitude",
        "position_unknown",
        "mission_item",
        "mission_unchecked",
        "survey_camera",
    )
