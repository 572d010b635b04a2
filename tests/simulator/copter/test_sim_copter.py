"""The simulated copter's flight logic, stepped directly in sim time (no sockets, no clock)."""

from __future__ import annotations

import math

import pytest

from simulator import DEFAULT_HOME, DT, Copter, CopterMode, CopterParams, MavResult
from simulator.mavconst import LandedState, MavState, ModeFlag, Severity
from simulator.vehicle import EKF_GPS_DELAY_S
from tests.support.copters import airborne, run_until, texts


def test_boots_disarmed_on_the_ground_in_stabilize() -> None:
    copter = Copter(DEFAULT_HOME)
    assert copter.mode is CopterMode.STABILIZE
    assert not copter.armed
    assert copter.system_status() is MavState.STANDBY
    assert copter.landed_state() is LandedState.ON_GROUND
    expected = ModeFlag.CUSTOM_MODE_ENABLED | ModeFlag.STABILIZE_ENABLED
    assert copter.base_mode() == expected | ModeFlag.MANUAL_INPUT_ENABLED  # 81, as SITL
    point = copter.position()
    assert (point.lat, point.lon, point.alt) == (DEFAULT_HOME.lat, DEFAULT_HOME.lon, 584.0)


def test_guided_takeoff_climbs_to_altitude_and_holds() -> None:
    copter = Copter(DEFAULT_HOME)
    copter.set_mode(CopterMode.GUIDED)
    assert copter.arm() is MavResult.ACCEPTED
    assert texts(copter) == ["Arming motors"]
    assert copter.base_mode() & ModeFlag.SAFETY_ARMED
    assert copter.system_status() is MavState.STANDBY  # armed but still landed
    assert copter.takeoff(10.0) is MavResult.ACCEPTED

    # the motors idle through ARMING_DELAY and spool-up before lifting off
    copter.advance(2.0)
    assert copter.body.alt == 0.0
    run_until(copter, lambda c: c.body.alt > 0.5, 5)
    assert copter.system_status() is MavState.ACTIVE
    assert copter.landed_state() is LandedState.TAKEOFF

    max_climb = 0.0
    while copter.time_s < 20.0:
        copter.advance(DT)
        max_climb = max(max_climb, copter.body.climb_rate)
    assert max_climb == pytest.approx(2.5, abs=0.01)  # WPNAV_SPEED_UP
    assert copter.body.alt == pytest.approx(10.0, abs=0.05)
    assert abs(copter.body.climb_rate) < 0.05
    assert copter.landed_state() is LandedState.IN_AIR
    copter.advance(30.0)
    assert copter.body.alt == pytest.approx(10.0, abs=0.01)
    assert math.hypot(copter.body.north, copter.body.east) < 0.01


@pytest.mark.parametrize(
    ("mode", "arm", "altitude"),
    [
        (CopterMode.GUIDED, False, 10.0),  # not armed
        (CopterMode.STABILIZE, True, 10.0),  # mode without user take-off
        (CopterMode.GUIDED, True, 0.0),  # not upwards
    ],
)
def test_takeoff_refused(mode: CopterMode, arm: bool, altitude: float) -> None:
    copter = Copter(DEFAULT_HOME)
    copter.set_mode(mode)
    if arm:
        copter.arm()
    assert copter.takeoff(altitude) is MavResult.FAILED
    copter.advance(5.0)
    assert copter.body.alt == 0.0


def test_takeoff_refused_when_already_flying() -> None:
    copter = airborne(10.0)
    assert copter.takeoff(20.0) is MavResult.FAILED


def test_loiter_takeoff_is_allowed() -> None:
    copter = Copter(DEFAULT_HOME)
    copter.set_mode(CopterMode.LOITER)
    copter.arm()
    assert copter.takeoff(5.0) is MavResult.ACCEPTED
    run_until(copter, lambda c: not c.taking_off, 20)
    assert copter.body.alt == pytest.approx(5.0, abs=0.15)
    # Then the transmitter's throttle rules: SITL's sits at its minimum, so LOITER sinks.
    copter.advance(2.0)
    assert copter.body.alt < 4.0


def test_land_descends_fast_then_slow_and_disarms_on_touchdown() -> None:
    copter = airborne(20.0)
    assert copter.set_mode(CopterMode.LAND) is MavResult.ACCEPTED
    assert copter.landed_state() is LandedState.LANDING
    run_until(copter, lambda c: c.body.alt < 16.0, 10)
    assert copter.body.climb_rate == pytest.approx(-1.5, abs=0.01)  # WPNAV_SPEED_DN
    run_until(copter, lambda c: c.body.alt < 5.0, 30)
    assert copter.body.climb_rate == pytest.approx(-0.5, abs=0.01)  # LAND_SPEED
    run_until(copter, lambda c: c.body.on_ground, 15, step_s=DT)
    assert copter.armed  # the land detector needs a second on the ground
    touchdown = copter.time_s
    run_until(copter, lambda c: not c.armed, 3, step_s=DT)
    assert copter.time_s - touchdown == pytest.approx(1.0, abs=0.05)
    assert texts(copter) == ["Disarming motors"]
    assert copter.mode is CopterMode.LAND
    assert copter.system_status() is MavState.STANDBY
    assert copter.body.alt == 0.0


def test_land_holds_its_horizontal_position() -> None:
    copter = airborne(10.0)
    target = copter.geo_of(north=30.0, east=0.0)
    copter.guided_goto(target.lat, target.lon, 10.0)
    run_until(copter, lambda c: c.body.north > 15.0, 30)
    copter.set_mode(CopterMode.LAND)  # lands near where it can stop, not at the target
    run_until(copter, lambda c: not c.armed, 60)
    assert 15.0 < copter.body.north < 30.0
    assert copter.body.groundspeed == 0.0


def test_rtl_climbs_returns_home_and_lands() -> None:
    copter = airborne(5.0)
    target = copter.geo_of(north=80.0, east=-60.0)  # 100 m away
    copter.guided_goto(target.lat, target.lon, 5.0)
    run_until(copter, lambda c: c.body.groundspeed < 0.05 and c.body.north > 79.9, 60)

    assert copter.set_mode(CopterMode.RTL) is MavResult.ACCEPTED
    # climbs straight up to RTL_ALT (15 m) before heading home
    run_until(copter, lambda c: c.body.alt > 14.5, 20)
    assert math.hypot(copter.body.north - 80.0, copter.body.east + 60.0) < 0.5
    max_alt = 0.0
    max_speed = 0.0
    while copter.armed and copter.time_s < 200.0:
        copter.advance(0.1)
        max_alt = max(max_alt, copter.body.alt)
        max_speed = max(max_speed, copter.body.groundspeed)
    assert not copter.armed
    assert max_alt == pytest.approx(15.0, abs=0.1)
    assert max_speed == pytest.approx(5.0, abs=0.01)
    assert math.hypot(copter.body.north, copter.body.east) < 0.1
    assert copter.body.alt == 0.0
    assert texts(copter) == ["Disarming motors"]


def test_rtl_near_home_climbs_only_the_cone() -> None:
    copter = airborne(3.0)
    target = copter.geo_of(north=2.0, east=0.0)
    copter.guided_goto(target.lat, target.lon, 3.0)
    copter.advance(10.0)
    copter.set_mode(CopterMode.RTL)
    peak = 0.0
    while copter.armed:
        copter.advance(0.1)
        peak = max(peak, copter.body.alt)
    # RTL_CONE_SLOPE: 2 m out, it climbs to max(2 m * 3, 3 m + 2.5 m) = 6 m, not 15 m
    assert peak == pytest.approx(6.0, abs=0.1)


def test_rtl_holds_altitude_when_above_rtl_alt() -> None:
    copter = airborne(30.0)
    start_alt = copter.body.alt
    copter.set_mode(CopterMode.RTL)
    copter.advance(4.9)  # loiters above home for RTL_LOIT_TIME before descending
    assert copter.body.alt == pytest.approx(start_alt, abs=0.01)
    copter.advance(1.0)
    assert copter.landed_state() is LandedState.LANDING
    assert copter.body.alt < start_alt - 0.1


@pytest.mark.parametrize("mode", [CopterMode.LAND, CopterMode.RTL, CopterMode.AUTO])
def test_arming_refused_in_modes_that_do_not_allow_it(mode: CopterMode) -> None:
    copter = Copter(DEFAULT_HOME)
    assert copter.set_mode(mode) is MavResult.ACCEPTED  # any mode may be chosen disarmed
    assert copter.arm() is MavResult.FAILED
    [text] = copter.drain_texts()
    assert text.severity is Severity.CRITICAL
    assert text.text == f"Arm: {mode.name} mode not armable"
    assert not copter.armed


def test_arming_refused_without_gps_fix_in_a_position_mode() -> None:
    copter = Copter(DEFAULT_HOME)
    copter.set_mode(CopterMode.GUIDED)
    copter.set_gps_fix(1)
    assert not copter.prearm_ok()
    assert copter.arm() is MavResult.FAILED
    assert texts(copter) == ["Arm: GPS 1: Bad fix"]
    assert copter.arm(force=True) is MavResult.FAILED  # a position is mandatory even forced
    assert texts(copter) == ["Arm: Need Position Estimate"]
    copter.set_gps_fix(3)
    # a good fix, but the EKF takes it only after 10 s of them (the field trial's wait)
    assert copter.arm() is MavResult.FAILED
    assert texts(copter) == ["Arm: Need Position Estimate"]
    copter.advance(EKF_GPS_DELAY_S - 1.0)
    assert not copter.position_ok
    copter.advance(1.0)
    assert copter.position_ok
    assert copter.arm() is MavResult.ACCEPTED


def test_stabilize_arms_without_gps_as_arducopter_does() -> None:
    copter = Copter(DEFAULT_HOME)
    copter.set_gps_fix(0)
    assert copter.arm() is MavResult.ACCEPTED


def test_force_arm_skips_the_mode_check() -> None:
    copter = Copter(DEFAULT_HOME)
    copter.set_mode(CopterMode.RTL)
    assert copter.arm(force=True) is MavResult.ACCEPTED


def test_disarm_in_flight_refused_unless_forced() -> None:
    copter = airborne(10.0)
    assert copter.disarm() is MavResult.FAILED
    assert copter.armed
    assert texts(copter) == []
    assert copter.disarm(force=True) is MavResult.ACCEPTED
    assert not copter.armed
    # no thrust: it falls
    run_until(copter, lambda c: c.body.on_ground, 5)
    assert copter.body.alt == 0.0


def test_disarm_on_the_ground_and_when_already_disarmed() -> None:
    copter = Copter(DEFAULT_HOME)
    assert copter.disarm() is MavResult.ACCEPTED  # nothing to do
    copter.arm()
    assert copter.disarm() is MavResult.ACCEPTED
    assert texts(copter) == ["Arming motors", "Disarming motors"]


def test_auto_disarm_after_disarm_delay_without_takeoff() -> None:
    copter = Copter(DEFAULT_HOME)
    copter.set_mode(CopterMode.GUIDED)
    copter.arm()
    copter.advance(9.9)
    assert copter.armed
    copter.advance(0.2)
    assert not copter.armed
    assert texts(copter) == ["Arming motors", "Disarming motors"]


def test_guided_goto_reaches_target_facing_the_direction_of_travel() -> None:
    copter = airborne(10.0)
    target = copter.geo_of(north=-40.0, east=30.0)  # 50 m south-east
    assert copter.guided_goto(target.lat, target.lon, 25.0) is MavResult.ACCEPTED
    copter.advance(6.0)  # accelerated, turned at ATC_SLEW_YAW, cruising
    assert copter.body.groundspeed == pytest.approx(5.0, abs=0.01)  # WPNAV_SPEED
    bearing = math.degrees(math.atan2(30.0, -40.0)) % 360.0
    assert math.degrees(copter.body.yaw) == pytest.approx(bearing, abs=0.5)
    copter.advance(34.0)
    point = copter.position()
    assert point.lat == pytest.approx(target.lat, abs=1e-7)
    assert point.lon == pytest.approx(target.lon, abs=1e-7)
    assert copter.relative_alt == pytest.approx(25.0, abs=0.02)
    assert copter.body.groundspeed < 0.01


def test_guided_goto_outside_guided_is_refused() -> None:
    copter = Copter(DEFAULT_HOME)
    assert copter.guided_goto(DEFAULT_HOME.lat, DEFAULT_HOME.lon, 10.0) is MavResult.FAILED


def test_acceleration_tilts_the_vehicle() -> None:
    copter = airborne(10.0)
    target = copter.geo_of(north=100.0, east=0.0)
    copter.guided_goto(target.lat, target.lon, 10.0)
    copter.advance(1.0)
    assert copter.body.pitch < math.radians(-5.0)  # nose down to accelerate north
    assert abs(copter.body.roll) < math.radians(0.5)
    assert copter.body.pitch > -CopterParams().angle_max


def test_stabilize_holds_altitude_and_brakes() -> None:
    copter = airborne(10.0)
    target = copter.geo_of(north=100.0, east=0.0)
    copter.guided_goto(target.lat, target.lon, 10.0)
    copter.advance(10.0)
    assert copter.set_mode(CopterMode.STABILIZE) is MavResult.ACCEPTED
    copter.advance(10.0)
    assert copter.body.groundspeed < 0.01
    assert copter.body.alt == pytest.approx(10.0, abs=0.05)


def test_mode_changes() -> None:
    copter = Copter(DEFAULT_HOME)
    assert copter.set_mode(99) is MavResult.FAILED
    assert texts(copter) == ["No such mode 99"]
    assert copter.set_mode(CopterMode.ALT_HOLD) is MavResult.FAILED  # real, not simulated
    assert copter.drain_texts()[0].severity is Severity.WARNING
    assert copter.set_mode(CopterMode.LOITER) is MavResult.ACCEPTED
    assert copter.base_mode() & ModeFlag.GUIDED_ENABLED


def test_auto_without_mission_refused_once_armed() -> None:
    copter = airborne(10.0)
    assert copter.set_mode(CopterMode.AUTO) is MavResult.FAILED
    assert texts(copter) == ["Mode change to AUTO failed: init failed"]
    assert copter.mode is CopterMode.GUIDED


def test_position_modes_refused_in_flight_without_gps() -> None:
    copter = airborne(10.0)
    copter.set_mode(CopterMode.STABILIZE)
    copter.set_gps_fix(0)
    assert copter.set_mode(CopterMode.LOITER) is MavResult.FAILED
    assert texts(copter) == ["Mode change to LOITER failed: requires position"]
    assert copter.set_mode(CopterMode.LAND) is MavResult.ACCEPTED  # LAND needs no GPS


def test_same_mode_keeps_the_guided_target() -> None:
    copter = airborne(10.0)
    target = copter.geo_of(north=50.0, east=0.0)
    copter.guided_goto(target.lat, target.lon, 10.0)
    assert copter.set_mode(CopterMode.GUIDED) is MavResult.ACCEPTED
    assert copter.guided_target == pytest.approx((50.0, 0.0, 10.0), abs=1e-6)  # ECEF round trip


def test_home_moves_to_where_it_arms() -> None:
    copter = airborne(10.0)
    target = copter.geo_of(north=20.0, east=20.0)
    copter.guided_goto(target.lat, target.lon, 0.0)  # down to the ground over there
    run_until(copter, lambda c: not c.armed, 60)  # lands, then DISARM_DELAY
    assert copter.home_ne == (0.0, 0.0)
    copter.arm()
    assert copter.home_ne == pytest.approx((20.0, 20.0), abs=0.01)
    assert copter.home.lat == pytest.approx(target.lat, abs=1e-7)


def test_battery_drains_with_load() -> None:
    idle = Copter(DEFAULT_HOME)
    idle.advance(60.0)
    flying = airborne(10.0)
    flying.advance(60.0 - flying.time_s)
    assert idle.battery.current_a == pytest.approx(0.5)
    assert flying.battery.current_a == pytest.approx(15.0, abs=0.5)
    assert flying.battery.consumed_mah > 20 * idle.battery.consumed_mah
    assert 14.0 < flying.battery.voltage < idle.battery.voltage <= 16.8
    assert flying.battery.remaining_pct < 100


def _state(copter: Copter) -> tuple[object, ...]:
    body = copter.body
    return (
        copter.time_s,
        copter.armed,
        copter.mode,
        copter.land_complete,
        body.north,
        body.east,
        body.down,
        body.vn,
        body.ve,
        body.vd,
        body.yaw,
        body.roll,
        body.pitch,
        copter.battery.consumed_mah,
    )


def _flight(slices: list[float]) -> tuple[object, ...]:
    copter = Copter(DEFAULT_HOME)
    copter.set_mode(CopterMode.GUIDED)
    copter.arm()
    copter.takeoff(12.0)
    for dt in slices[: len(slices) // 2]:
        copter.advance(dt)
    target = copter.geo_of(north=30.0, east=40.0)
    copter.guided_goto(target.lat, target.lon, 20.0)
    for dt in slices[len(slices) // 2 :]:
        copter.advance(dt)
    return _state(copter)


def test_physics_independent_of_how_time_is_sliced() -> None:
    """The same 40 s, in one step per half, in physics steps, and in odd slices."""
    whole = _flight([20.0, 20.0])
    fine = _flight([DT] * 2000)
    odd = _flight([0.013] * 1538 + [0.006] + [0.013] * 1538 + [0.006])
    assert whole == fine == odd
    assert whole[0] == pytest.approx(40.0)


def test_advance_to_is_absolute() -> None:
    copter = Copter(DEFAULT_HOME)
    copter.advance_to(5.0)
    copter.advance_to(3.0)  # a clock never runs backwards; ignored
    assert copter.time_s == pytest.approx(5.0)
