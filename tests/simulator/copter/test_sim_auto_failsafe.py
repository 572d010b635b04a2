"""AUTO missions, parameter effects, the battery failsafe, wind and GPS noise, in sim time."""

from __future__ import annotations

import math

import pytest

from simulator import DEFAULT_HOME, Copter, CopterMode, MavResult
from simulator.mavconst import MavCmd, MavFrame, MavState, MissionState
from simulator.params.table import SetOutcome
from simulator.vehicle import ItemReached, PhotoTaken
from simulator.vehicle.stored_mission import MissionItem
from tests.support.copters import airborne, run_until, texts

REL = MavFrame.GLOBAL_RELATIVE_ALT_INT


def at(copter: Copter, north: float, east: float) -> tuple[int, int]:
    point = copter.geo_of(north=north, east=east)
    return round(point.lat * 1e7), round(point.lon * 1e7)


def mission(copter: Copter) -> list[MissionItem]:
    x1, y1 = at(copter, 40.0, 0.0)
    x2, y2 = at(copter, 40.0, 30.0)
    return [
        MissionItem(0, MavFrame.GLOBAL, MavCmd.NAV_WAYPOINT),
        MissionItem(1, REL, MavCmd.NAV_TAKEOFF, z=10.0),
        MissionItem(2, MavFrame.MISSION, MavCmd.DO_CHANGE_SPEED, 1.0, 3.0),
        MissionItem(3, MavFrame.MISSION, MavCmd.DO_SET_CAM_TRIGG_DIST, 10.0),
        MissionItem(4, REL, MavCmd.NAV_WAYPOINT, x=x1, y=y1, z=12.0),
        MissionItem(5, REL, MavCmd.NAV_LOITER_TIME, 3.0, x=x2, y=y2, z=12.0),
        MissionItem(6, MavFrame.MISSION, MavCmd.DO_SET_CAM_TRIGG_DIST, 0.0),
        MissionItem(7, MavFrame.MISSION, MavCmd.DO_DIGICAM_CONTROL, x=1),
        MissionItem(8, REL, MavCmd.NAV_RETURN_TO_LAUNCH),
    ]


def test_auto_flies_the_mission_from_the_ground() -> None:
    copter = Copter(DEFAULT_HOME)
    copter.set_mode(CopterMode.GUIDED)
    copter.arm()
    assert copter.set_mode(CopterMode.AUTO) is MavResult.FAILED  # no mission yet
    copter.set_mission(mission(copter))
    assert copter.mission_state() is MissionState.NOT_STARTED
    assert copter.set_mode(CopterMode.AUTO) is MavResult.ACCEPTED
    copter.drain_texts()
    events: list[object] = []
    max_speed = 0.0

    def done(c: Copter) -> bool:
        nonlocal max_speed
        events.extend(c.drain_events())
        if 4 <= c.mission_current <= 5:
            max_speed = max(max_speed, c.body.groundspeed)
        return not c.armed

    run_until(copter, done, 200)
    reached = [e.seq for e in events if isinstance(e, ItemReached)]
    assert reached == [1, 4, 5, 8]
    assert max_speed == pytest.approx(3.0, abs=0.05)  # DO_CHANGE_SPEED ran during the flight
    photos = [e for e in events if isinstance(e, PhotoTaken)]
    # Every 10 m along both legs: the "do" commands after the loiter run once it is over
    # (AP_Mission's order), so the trigger stops there and DIGICAM takes one more there.
    assert 6 <= len(photos) <= 8
    on_second_leg = [p for p in photos if copter.ne_of(p.lat, p.lon)[1] > 15.0]
    assert len(on_second_leg) >= 2
    assert [p.index for p in photos] == list(range(1, len(photos) + 1))
    said = texts(copter)
    assert "Reached command #4" in said
    assert said[-1] == "Disarming motors"
    assert math.hypot(copter.body.north, copter.body.east) < 2.5  # landed at home
    assert copter.mission_state() is MissionState.COMPLETE


def test_auto_needs_a_takeoff_on_the_ground_and_resumes_in_the_air() -> None:
    copter = Copter(DEFAULT_HOME)
    x, y = at(copter, 20.0, 0.0)
    copter.set_mission(
        [
            MissionItem(0, MavFrame.GLOBAL, MavCmd.NAV_WAYPOINT),
            MissionItem(1, REL, MavCmd.NAV_WAYPOINT, 2.0, x=x, y=y, z=10.0),
            MissionItem(2, REL, MavCmd.NAV_LAND),
        ]
    )
    copter.set_mode(CopterMode.GUIDED)
    copter.arm()
    assert copter.set_mode(CopterMode.AUTO) is MavResult.FAILED
    assert texts(copter)[-2:] == [
        "Auto: Missing Takeoff Cmd",
        "Mode change to AUTO failed: init failed",
    ]
    flying = airborne(10.0)
    flying.set_mission(copter.mission)
    assert flying.set_mode(CopterMode.AUTO) is MavResult.ACCEPTED
    assert flying.mission_state() is MissionState.ACTIVE
    assert not flying.clear_mission()  # not while it runs
    run_until(flying, lambda c: not c.armed, 120)
    assert flying.body.north == pytest.approx(20.0, abs=2.5)
    assert [e.seq for e in flying.drain_events() if isinstance(e, ItemReached)] == [1, 2]


def test_a_mission_uploaded_after_one_was_flown_starts_from_its_take_off() -> None:
    copter = Copter(DEFAULT_HOME)
    copter.set_mission(mission(copter))
    copter.set_mode(CopterMode.GUIDED)
    copter.arm()
    assert copter.set_mode(CopterMode.AUTO) is MavResult.ACCEPTED
    run_until(copter, lambda c: not c.armed, 200)
    assert copter.mode is CopterMode.AUTO  # landed and disarmed, still in AUTO

    # The next flight's plan, uploaded as a GCS does after a flight.
    copter.set_mission(mission(copter))
    assert copter.mission_state() is MissionState.NOT_STARTED
    copter.set_mode(CopterMode.GUIDED)
    copter.arm()
    assert copter.set_mode(CopterMode.AUTO) is MavResult.ACCEPTED, texts(copter)[-2:]
    copter.drain_events()
    run_until(copter, lambda c: not c.armed, 200)
    assert [e.seq for e in copter.drain_events() if isinstance(e, ItemReached)] == [1, 4, 5, 8]


def test_wpnav_speed_changes_guided_cruise_speed() -> None:
    copter = airborne(10.0)
    assert copter.set_param("WPNAV_SPEED", 800.0) is SetOutcome.STORED
    assert copter.params.wpnav_speed == 8.0
    target = copter.geo_of(north=200.0, east=0.0)
    copter.guided_goto(target.lat, target.lon, 10.0)
    copter.advance(15.0)
    assert copter.body.groundspeed == pytest.approx(8.0, abs=0.01)
    assert copter.set_param("WPNAV_SPEED", 5.0) is SetOutcome.REFUSED  # below 20 cm/s
    assert copter.set_param("NOPE", 1.0) is SetOutcome.UNKNOWN
    assert copter.set_param("DISARM_DELAY", 3.7) is SetOutcome.STORED
    assert copter.params.disarm_delay == 4  # an integer parameter rounds


def test_rtl_alt_parameter_sets_the_return_altitude() -> None:
    copter = airborne(5.0)
    copter.set_param("RTL_ALT", 2500)
    target = copter.geo_of(north=30.0, east=0.0)
    copter.guided_goto(target.lat, target.lon, 5.0)
    copter.advance(15.0)
    copter.set_mode(CopterMode.RTL)
    run_until(copter, lambda c: c.body.alt > 24.5, 30)


@pytest.mark.parametrize(
    ("action", "mode"), [(0, CopterMode.GUIDED), (1, CopterMode.LAND), (2, CopterMode.RTL)]
)
def test_battery_failsafe(action: int, mode: CopterMode) -> None:
    copter = airborne(10.0)
    copter.set_param("BATT_FS_LOW_ACT", action)
    copter.set_param("SIM_BATT_DRAIN", 200.0)
    run_until(copter, lambda c: c.battery_failsafe, 120)
    said = texts(copter)
    assert said[0].startswith("Battery 1 is low ")
    assert copter.mode is mode
    assert copter.system_status() is MavState.CRITICAL
    assert copter.battery.voltage < copter.params.batt_low_volt


def test_battery_failsafe_on_remaining_capacity() -> None:
    copter = airborne(10.0)
    copter.set_param("BATT_FS_LOW_ACT", 1)
    copter.set_param("BATT_LOW_MAH", 4900)
    run_until(copter, lambda c: c.battery_failsafe, 60)
    assert copter.mode is CopterMode.LAND
    assert copter.battery.remaining_mah < 4900


def test_gps_noise_is_seeded_and_sized() -> None:
    def samples(seed: int) -> list[tuple[float, float, float]]:
        copter = Copter(DEFAULT_HOME, seed=seed)
        copter.set_param("SIM_GPS_NOISE", 2.0)
        out = []
        for _ in range(200):
            copter.advance(0.2)
            out.append(copter.gps_error)
        return out

    first = samples(1)
    assert first == samples(1)
    assert first != samples(2)
    rms = math.sqrt(sum(n * n + e * e for n, e, _ in first) / (2 * len(first)))
    assert rms == pytest.approx(2.0, rel=0.25)
    default = Copter(DEFAULT_HOME)
    default.advance(1.0)
    assert max(abs(v) for v in default.gps_error) < 1.0  # default noise is small


def test_wind_leans_the_hover_and_shows_as_airspeed() -> None:
    copter = airborne(10.0)
    copter.set_param("SIM_WIND_SPD", 8.0)
    copter.set_param("SIM_WIND_DIR", 0.0)  # from the north
    copter.advance(5.0)
    assert copter.body.groundspeed < 0.01  # the position controller holds station
    assert copter.body.pitch < -math.radians(3.0)  # nose down, into the wind (facing north)
    assert math.hypot(*copter.body.airspeed_ne(copter.params)) == pytest.approx(8.0, abs=0.05)


def test_a_mission_flown_to_the_end_starts_again_from_its_take_off_next_time() -> None:
    # AP_Arming_Copter::disarm resets the mission: a survey uploaded while the vehicle sits
    # disarmed in AUTO after its last one takes off again rather than "Missing Takeoff Cmd".
    copter = Copter(DEFAULT_HOME)
    copter.set_mission(mission(copter))
    copter.set_mode(CopterMode.GUIDED)
    copter.arm()
    assert copter.set_mode(CopterMode.AUTO) is MavResult.ACCEPTED
    run_until(copter, lambda c: not c.armed, 200)
    assert copter.mode is CopterMode.AUTO
    copter.set_mission(mission(copter))
    assert copter.mission_current == 0
    copter.set_mode(CopterMode.GUIDED)
    copter.arm()
    assert copter.set_mode(CopterMode.AUTO) is MavResult.ACCEPTED
    run_until(copter, lambda c: c.relative_alt > 5, 60)
