"""A new home against the rails: RTL and the failsafes fly to home, so a home outside the
geofence, or beyond the range limit, is refused."""

from __future__ import annotations

import math
from dataclasses import replace

import pytest

from backend.fleet.registry import VehicleRecord
from backend.safety import SafetyRails, check_set_home
from backend.safety.rails_store import vehicle_scope
from backend.safety.schemas import SafetyRailsModel
from backend.safety.service import SafetyService
from backend.settings import HubSettings
from protocol.messages import HoldCommand, SetHomeCommand, VehicleState
from tests.unit.safety.shapes import UNKNOWN, geo, north_of, u_fence, vehicle


def test_a_home_inside_the_fence_is_allowed_and_no_rails_allow_anything() -> None:
    rails = SafetyRails(geofence=u_fence())
    inside = geo(50, 250)
    assert check_set_home(rails, vehicle(), inside.lat, inside.lon) == []
    far = geo(5000, 5000)
    assert check_set_home(SafetyRails(), vehicle(), far.lat, far.lon) == []


def test_a_home_outside_the_fence_is_refused() -> None:
    outside = geo(150, 250)  # in the notch of the U
    [violation] = check_set_home(
        SafetyRails(geofence=u_fence()), vehicle(), outside.lat, outside.lon
    )
    assert violation.rule == "geofence"
    assert violation.message == "new home is 50 m outside the geofence: RTL would fly there"
    assert violation.value == pytest.approx(50, abs=0.5)


def test_a_home_across_the_notch_is_refused_because_rtl_flies_straight() -> None:
    rails = SafetyRails(geofence=u_fence())
    across = geo(250, 250)
    [violation] = check_set_home(rails, vehicle(at=geo(50, 250)), across.lat, across.lon)
    assert violation.rule == "geofence"
    assert "straight leg" in violation.message
    assert check_set_home(rails, vehicle(at=geo(250, 50)), across.lat, across.lon) == []


def test_home_here_is_checked_where_the_vehicle_is() -> None:
    rails = SafetyRails(geofence=u_fence())
    assert check_set_home(rails, vehicle(at=geo(50, 50)), None, None) == []
    [violation] = check_set_home(rails, vehicle(at=geo(150, 250)), None, None)
    assert violation.message == (
        "the vehicle's position (the new home) is 50 m outside the geofence: RTL would fly there"
    )


def test_home_may_not_move_beyond_the_range_limit() -> None:
    rails = SafetyRails(max_distance_from_home_m=500)
    home = geo(50, 50)
    near, far = north_of(home, 400), north_of(home, 812)
    assert check_set_home(rails, vehicle(home=home), near.lat, near.lon) == []
    [violation] = check_set_home(rails, vehicle(home=home), far.lat, far.lon)
    assert violation.rule == "max_distance_from_home"
    assert violation.message == "new home is 812 m from home; the limit is 500 m"


def test_unknowns_fail_closed_and_nan_is_an_error() -> None:
    rails = SafetyRails(geofence=u_fence(), max_distance_from_home_m=500)
    target = geo(50, 250)
    [violation] = check_set_home(rails, UNKNOWN, target.lat, target.lon)
    assert violation.rule == "position_unknown"
    assert "geofence and max_distance_from_home" in violation.message
    with pytest.raises(ValueError, match="not a valid latitude"):
        check_set_home(rails, vehicle(), math.nan, target.lon)


class _Rails:
    """The rails repository, holding one vehicle's rails (a fence around the U)."""

    def __init__(self, stored: str) -> None:
        self.stored = stored
        self.reads = 0

    def get(self, scope: str) -> str | None:
        self.reads += 1
        return self.stored if scope == vehicle_scope("v1") else None


def gate_with_fence() -> tuple[SafetyService, _Rails, VehicleRecord]:
    fence = {"polygon": [{"lat": p.lat, "lon": p.lon} for p in u_fence().polygon]}
    rails = _Rails(SafetyRailsModel.model_validate({"geofence": fence}).model_dump_json())
    settings = HubSettings(environment="development", admin_password="x" * 12)
    here = geo(50, 50)
    state = VehicleState(
        lat=here.lat,
        lon=here.lon,
        alt_rel=10,
        armed=True,
        home_lat=here.lat,
        home_lon=here.lon,
        home_alt_msl=500,
        battery_remaining=80,
    )
    record = VehicleRecord("v1", "ardupilot", "multirotor", [], state=state)
    return SafetyService(rails, settings), rails, record  # type: ignore[arg-type]


def test_the_gate_checks_a_new_home_and_never_holds_back_hold() -> None:
    gate, rails, record = gate_with_fence()
    outside = geo(150, 250)
    far = SetHomeCommand(use_current=False, lat=outside.lat, lon=outside.lon, alt_msl=500)
    [violation] = gate.check_command(record, far)
    assert violation.rule == "geofence"
    [airborne] = gate.check_command(record, SetHomeCommand())  # here, but 10 m up
    assert airborne.rule == "home_altitude"
    reads = rails.reads
    assert gate.check_command(record, HoldCommand()) == []
    assert rails.reads == reads  # decided without reading any rails


def test_home_is_not_taken_from_a_vehicle_in_the_air() -> None:
    [violation] = check_set_home(SafetyRails(), vehicle(alt=30.0, landed=False), None, None)
    assert violation.rule == "home_altitude"
    assert "in the air" in violation.message
    assert check_set_home(SafetyRails(), vehicle(), None, None) == []


def test_a_home_that_moves_every_altitude_is_refused() -> None:
    here = replace(vehicle(), home_alt_msl=584.0)
    point = geo(60, 60)
    assert check_set_home(SafetyRails(), here, point.lat, point.lon, 590.0) == []
    [violation] = check_set_home(SafetyRails(), here, point.lat, point.lon, 884.0)
    assert violation.rule == "home_altitude"
    assert violation.value == pytest.approx(300.0)
    assert "+300.0 m from the current home's altitude" in violation.message
    # Without home's altitude there is nothing to compare with: refused, saying why.
    [unknown] = check_set_home(SafetyRails(), vehicle(), point.lat, point.lon, 590.0)
    assert unknown.rule == "position_unknown"
    assert "home altitude" in unknown.message
