from __future__ import annotations

from dataclasses import replace

import pytest

from backend.safety import BatteryModel, SafetyRails, Waypoint, check_plan, estimate_plan
from tests.unit.safety.shapes import UNKNOWN, geo, north_of, vehicle

HOME = geo(0, 0)
KM_NORTH = north_of(HOME, 1000)


def test_one_km_out_and_back() -> None:
    estimate = estimate_plan(vehicle(at=HOME), [Waypoint(KM_NORTH.lat, KM_NORTH.lon, 20)])
    # Climb 20 m at 2.5 m/s, 1 km out and 1 km back at 5 m/s, descend 20 m at 1.5 m/s.
    seconds = 20 / 2.5 + 1000 / 5 + 1000 / 5 + 20 / 1.5
    assert estimate.flight_time_s == pytest.approx(seconds)
    assert estimate.distance_m == pytest.approx(2000)
    # 15 A for 421.3 s is 1.756 Ah of a 5 Ah pack.
    assert estimate.required_pct == pytest.approx(15 * seconds / 3600 / 5 * 100)
    assert estimate.required_pct == pytest.approx(35.11, abs=0.01)
    assert estimate.available_pct == 90


def test_estimate_from_a_flying_vehicle_descends_and_climbs() -> None:
    flying = vehicle(at=KM_NORTH, home=HOME, alt=50, landed=False, battery=None)
    estimate = estimate_plan(flying, [Waypoint(KM_NORTH.lat, KM_NORTH.lon, 20)])
    # Down 30 m, home 1 km, down 20 m to land.
    assert estimate.flight_time_s == pytest.approx(30 / 1.5 + 1000 / 5 + 20 / 1.5)
    assert estimate.available_pct is None


def test_a_landed_vehicle_without_an_altitude_reading_is_on_the_ground() -> None:
    landed = vehicle(at=HOME, alt=None)
    estimate = estimate_plan(landed, [Waypoint(HOME.lat, HOME.lon, 30)])
    assert estimate.flight_time_s == pytest.approx(30 / 2.5 + 30 / 1.5)


def test_the_model_scales_the_estimate() -> None:
    model = BatteryModel(capacity_mah=10_000, hover_current_a=30, cruise_speed_m_s=10)
    estimate = estimate_plan(vehicle(at=HOME), [Waypoint(KM_NORTH.lat, KM_NORTH.lon, 20)], model)
    seconds = 20 / 2.5 + 2000 / 10 + 20 / 1.5
    assert estimate.required_pct == pytest.approx(30 * seconds / 3600 / 10 * 100)


def test_the_reserve_decides_sufficiency() -> None:
    route = [Waypoint(KM_NORTH.lat, KM_NORTH.lon, 20)]  # needs 35.1%
    assert check_plan(SafetyRails(), vehicle(at=HOME, battery=55.2), route) == []
    [violation] = check_plan(SafetyRails(), vehicle(at=HOME, battery=55.0), route)
    assert violation.rule == "battery_sufficiency"
    assert violation.message == (
        "mission needs about 35% of the battery plus a 20% reserve; 55% remains"
    )
    assert violation.limit == 55.0
    assert violation.value == pytest.approx(55.11, abs=0.01)
    assert check_plan(SafetyRails(battery_reserve_pct=0), vehicle(at=HOME, battery=36), route) == []


def test_estimate_needs_position_and_home() -> None:
    with pytest.raises(ValueError, match="position, home position and altitude"):
        estimate_plan(replace(UNKNOWN, landed=False), [])


def test_battery_model_refuses_nonsense() -> None:
    with pytest.raises(ValueError, match="capacity_mah 0"):
        BatteryModel(capacity_mah=0)
