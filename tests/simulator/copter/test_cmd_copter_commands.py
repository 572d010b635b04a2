"""The operator commands on the simulated copter: BRAKE, DO_CHANGE_SPEED, DO_SET_HOME,
PREFLIGHT_REBOOT_SHUTDOWN and the forced disarm, as ArduCopter answers them."""

from __future__ import annotations

import math
import time
from typing import Any

import pytest
from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from simulator import DEFAULT_HOME, Copter, CopterMode, LocalFrame, MavResult
from simulator import server as server_module
from simulator.config import ListenAddress, SimulatorConfig
from simulator.mavconst import FORCE_REBOOT_MAGIC, MavCmd, MavFrame, ModeFlag
from simulator.vehicle.stored_mission import MissionItem
from tests.support.copters import Vehicle, ack_of, airborne, kinds, run_until, texts
from tests.support.simulators import SYSID, mavlink_client, serving, wait_for

_FRAME = LocalFrame(DEFAULT_HOME.lat, DEFAULT_HOME.lon, DEFAULT_HOME.alt)
NORTH = _FRAME.to_geo(0.0, 1.0)[0] - DEFAULT_HOME.lat  # degrees of latitude per metre


def east_deg(metres: float) -> float:
    return _FRAME.to_geo(metres, 0.0)[1] - DEFAULT_HOME.lon


def cruising_north(copter: Copter) -> None:
    """In GUIDED, on its way to a point 300 m north, at full speed."""
    here = copter.position()
    assert copter.guided_goto(here.lat + 300 * NORTH, here.lon, 10.0) is MavResult.ACCEPTED
    run_until(copter, lambda c: c.body.groundspeed > 4.99, 30)


# -- BRAKE: what "hold" is on ArduCopter -----------------------------------------------


def test_brake_stops_hard_and_holds() -> None:
    copter = airborne()
    cruising_north(copter)
    speed = copter.body.groundspeed
    braked_at = copter.body.north
    assert copter.set_mode(CopterMode.BRAKE) is MavResult.ACCEPTED
    assert copter.base_mode() & ModeFlag.GUIDED_ENABLED
    run_until(copter, lambda c: c.body.groundspeed < 0.05, 5)
    # BRAKE_MODE_DECEL_RATE is 7.5 m/s/s: a stop in v^2/2a, three times harder than WPNAV
    assert copter.body.north - braked_at == pytest.approx(speed**2 / (2 * 7.5), abs=0.5)
    stopped = (copter.body.north, copter.body.east, copter.body.alt)
    copter.advance(20.0)
    assert math.dist(stopped, (copter.body.north, copter.body.east, copter.body.alt)) < 0.1
    assert copter.mode is CopterMode.BRAKE  # no timeout: it stays until told otherwise


def test_brake_is_not_armable_and_disarms_a_landed_copter() -> None:
    copter = Copter(DEFAULT_HOME)
    copter.set_mode(CopterMode.BRAKE)
    assert copter.arm() is MavResult.FAILED
    assert texts(copter) == ["Arm: BRAKE mode not armable"]

    copter.set_mode(CopterMode.GUIDED)
    assert copter.arm() is MavResult.ACCEPTED
    assert copter.set_mode(CopterMode.BRAKE) is MavResult.ACCEPTED
    copter.advance(0.1)
    assert not copter.armed  # ModeBrake::run: landed, so disarm


def test_brake_needs_a_position_when_armed() -> None:
    copter = airborne()
    copter.set_gps_fix(1)
    assert copter.set_mode(CopterMode.BRAKE) is MavResult.FAILED
    assert texts(copter) == ["Mode change to BRAKE failed: requires position"]


# -- DO_CHANGE_SPEED -------------------------------------------------------------------


def test_change_speed_sets_the_guided_cruise_speed() -> None:
    vehicle = Vehicle()
    vehicle.fly()
    cruising_north(vehicle.copter)
    replies = vehicle.command(MavCmd.DO_CHANGE_SPEED, 1, 2.0, -1)
    assert ack_of(replies).result == MavResult.ACCEPTED
    vehicle.copter.advance(5.0)
    assert vehicle.copter.body.groundspeed == pytest.approx(2.0, abs=0.01)
    # climb and descent speeds are their own kinds; a speed must be above zero
    assert ack_of(vehicle.command(MavCmd.DO_CHANGE_SPEED, 2, 1.0)).result == MavResult.ACCEPTED
    assert ack_of(vehicle.command(MavCmd.DO_CHANGE_SPEED, 1, 0.0)).result == MavResult.FAILED
    # GUIDED starts again at WPNAV_SPEED
    vehicle.copter.set_mode(CopterMode.LOITER)
    vehicle.copter.set_mode(CopterMode.GUIDED)
    cruising_north(vehicle.copter)


def test_change_speed_outside_guided_and_auto_fails() -> None:
    vehicle = Vehicle()
    vehicle.fly()
    vehicle.copter.set_mode(CopterMode.LOITER)
    assert ack_of(vehicle.command(MavCmd.DO_CHANGE_SPEED, 1, 3.0)).result == MavResult.FAILED


def test_mission_change_speed_paces_the_waypoints() -> None:
    copter = airborne()
    far = copter.position()
    copter.set_mission(
        [
            MissionItem(0, MavFrame.GLOBAL, MavCmd.NAV_WAYPOINT),
            MissionItem(1, MavFrame.MISSION, MavCmd.DO_CHANGE_SPEED, 1.0, 3.0),
            MissionItem(
                2,
                MavFrame.GLOBAL_RELATIVE_ALT,
                MavCmd.NAV_WAYPOINT,
                x=round((far.lat + 200 * NORTH) * 1e7),
                y=round(far.lon * 1e7),
                z=10.0,
            ),
        ]
    )
    assert copter.set_mode(CopterMode.AUTO) is MavResult.ACCEPTED
    copter.advance(15.0)
    assert copter.body.groundspeed == pytest.approx(3.0, abs=0.01)


# -- DO_SET_HOME -----------------------------------------------------------------------


def home_of(replies: list[Any]) -> Any:
    [home] = [r for r in replies if r.message.get_type() == "HOME_POSITION"]
    assert not home.to_sender_only  # sent to every GCS, as Copter::set_home does
    return home.message


def test_set_home_here_in_flight_takes_the_altitude_too() -> None:
    vehicle = Vehicle()
    vehicle.fly()
    cruising_north(vehicle.copter)
    vehicle.copter.guided_hold()
    vehicle.copter.advance(5.0)
    here = vehicle.copter.position()
    replies = vehicle.command(MavCmd.DO_SET_HOME, 1)
    assert kinds(replies) == ["COMMAND_ACK", "HOME_POSITION"]
    assert ack_of(replies).result == MavResult.ACCEPTED
    home = home_of(replies)
    assert (home.latitude, home.longitude) == (round(here.lat * 1e7), round(here.lon * 1e7))
    assert home.altitude == round(here.alt * 1000)
    # ArduCopter's gotcha: home at the vehicle's altitude makes it 0 m above home
    assert vehicle.copter.relative_alt == pytest.approx(0.0, abs=1e-6)


def test_set_home_to_a_point_then_rtl_flies_there_and_lands() -> None:
    vehicle = Vehicle()
    vehicle.fly()
    start = vehicle.copter.position()
    lat, lon = start.lat + 40 * NORTH, start.lon + east_deg(30)
    # COMMAND_INT: a float32 COMMAND_LONG parameter holds a latitude to about a metre
    x, y = round(lat * 1e7), round(lon * 1e7)
    replies = vehicle.command_int(MavCmd.DO_SET_HOME, MavFrame.GLOBAL, [0], x, y, DEFAULT_HOME.alt)
    assert ack_of(replies).result == MavResult.ACCEPTED
    home = home_of(replies)
    assert (home.latitude, home.longitude) == (x, y)
    assert home.altitude == round(DEFAULT_HOME.alt * 1000)
    assert vehicle.copter.relative_alt == pytest.approx(10.0, abs=0.1)

    assert ack_of(vehicle.command(MavCmd.NAV_RETURN_TO_LAUNCH)).result == MavResult.ACCEPTED
    run_until(vehicle.copter, lambda c: not c.armed, 120)
    landed = vehicle.copter.position()
    north, east = vehicle.copter.ne_of(landed.lat, landed.lon)
    assert math.dist((north, east), vehicle.copter.ne_of(lat, lon)) < 1.0


def test_set_home_is_locked_against_arming_and_refused_far_from_the_origin() -> None:
    vehicle = Vehicle()
    lat, lon = DEFAULT_HOME.lat + 20 * NORTH, DEFAULT_HOME.lon
    assert ack_of(vehicle.command(MavCmd.DO_SET_HOME, 0, 0, 0, 0, lat, lon, 590)).result == 0
    vehicle.copter.set_mode(CopterMode.GUIDED)
    vehicle.copter.arm()
    assert vehicle.copter.home.lat == pytest.approx(lat)  # arming moves only an unlocked home
    far = DEFAULT_HOME.lat + 60_000 * NORTH  # AP_AHRS keeps home within 50 km of the origin
    replies = vehicle.command(MavCmd.DO_SET_HOME, 0, 0, 0, 0, far, lon, 590)
    assert ack_of(replies).result == MavResult.FAILED
    assert "HOME_POSITION" not in kinds(replies)


# -- the forced disarm -------------------------------------------------------------------


def test_plain_disarm_in_flight_is_refused_silently_forced_one_drops_it() -> None:
    vehicle = Vehicle()
    vehicle.fly()
    replies = vehicle.command(MavCmd.COMPONENT_ARM_DISARM, 0)
    assert kinds(replies) == ["COMMAND_ACK"]  # AP_Arming_Copter::disarm says nothing
    assert ack_of(replies).result == MavResult.FAILED
    assert vehicle.copter.armed
    replies = vehicle.command(MavCmd.COMPONENT_ARM_DISARM, 0, 21196)
    assert ack_of(replies).result == MavResult.ACCEPTED
    assert not vehicle.copter.armed
    run_until(vehicle.copter, lambda c: c.body.on_ground, 10)


# -- PREFLIGHT_REBOOT_SHUTDOWN -----------------------------------------------------------


def test_reboot_refused_while_armed_unless_forced() -> None:
    vehicle = Vehicle()
    vehicle.copter.set_mode(CopterMode.GUIDED)
    vehicle.copter.arm()
    vehicle.copter.drain_texts()
    replies = vehicle.command(MavCmd.PREFLIGHT_REBOOT_SHUTDOWN, 1)
    assert kinds(replies) == ["COMMAND_ACK"]  # handle_preflight_reboot: FAILED, no text
    assert ack_of(replies).result == MavResult.FAILED
    assert not vehicle.copter.reboot_requested
    # 3 (stay in the bootloader) is not simulated
    assert ack_of(vehicle.command(MavCmd.PREFLIGHT_REBOOT_SHUTDOWN, 3)).result == 3
    forced = vehicle.command(MavCmd.PREFLIGHT_REBOOT_SHUTDOWN, 1, 0, 0, 0, 0, FORCE_REBOOT_MAGIC)
    assert ack_of(forced).result == MavResult.ACCEPTED
    assert vehicle.copter.reboot_requested


def test_a_rebooted_copter_keeps_what_the_board_stores() -> None:
    copter = airborne()
    cruising_north(copter)
    copter.set_mode(CopterMode.LAND)
    run_until(copter, lambda c: not c.armed, 120)
    assert copter.set_param("WPNAV_SPEED", 700) == "stored"
    mission = [MissionItem(0, 0, 16), MissionItem(1, 3, 22, z=10)]
    copter.set_mission(mission)
    where = copter.position()
    assert copter.request_reboot(1, force=False) is MavResult.ACCEPTED

    rebooted = copter.rebooted(boot_at=123.0)
    assert rebooted.mode is CopterMode.STABILIZE
    assert not rebooted.armed
    assert not rebooted.reboot_requested
    assert rebooted.time_s == 0.0
    assert rebooted.param_table.get("WPNAV_SPEED") == 700
    assert rebooted.params.wpnav_speed == 7.0
    assert rebooted.mission == mission
    assert rebooted.battery is copter.battery
    here = rebooted.position()
    assert (here.lat, here.lon) == pytest.approx((where.lat, where.lon))
    assert rebooted.home.lat == pytest.approx(where.lat)  # a new EKF origin, where it is
    rebooted.advance_to(123.5)  # its clock starts at its boot
    assert rebooted.time_s == pytest.approx(0.5)


def test_reboot_over_tcp_acks_goes_quiet_and_comes_back_fresh(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    monkeypatch.setattr(server_module, "REBOOT_SILENCE_S", 1.0)
    config = SimulatorConfig(
        listen=ListenAddress("tcp", "127.0.0.1", 0), system_id=SYSID, speedup=10.0
    )
    with (
        serving(config) as (_server, address),
        mavlink_client(f"tcp:127.0.0.1:{address.port}") as gcs,
    ):
        wait_for(gcs, ["HEARTBEAT"], lambda m: True, 10, "a heartbeat")
        gcs.mav.command_long_send(SYSID, 1, mavlink2.MAV_CMD_DO_SET_MODE, 0, 1, 4, 0, 0, 0, 0, 0)
        wait_for(gcs, ["HEARTBEAT"], lambda m: m.custom_mode == 4, 5, "GUIDED")
        booted = wait_for(
            gcs, ["ATTITUDE"], lambda m: m.time_boot_ms > 20_000, 10, "20 s since boot"
        )

        gcs.mav.command_long_send(
            SYSID, 1, mavlink2.MAV_CMD_PREFLIGHT_REBOOT_SHUTDOWN, 0, 1, 0, 0, 0, 0, 0, 0
        )
        ack = wait_for(
            gcs,
            ["COMMAND_ACK"],
            lambda m: m.command == mavlink2.MAV_CMD_PREFLIGHT_REBOOT_SHUTDOWN,
            5,
            "the reboot's ACK",
        )
        assert ack.result == mavlink2.MAV_RESULT_ACCEPTED
        acked_at = time.monotonic()
        back = wait_for(gcs, ["HEARTBEAT"], lambda m: True, 10, "the heartbeat after the reboot")
        assert time.monotonic() - acked_at >= 0.9  # a second of silence first
        assert back.custom_mode == CopterMode.STABILIZE  # the initial mode again
        attitude = wait_for(gcs, ["ATTITUDE"], lambda m: True, 5, "attitude after the reboot")
        # its clock started again at the reboot: 1 s of silence is 10 s at this speed-up
        assert attitude.time_boot_ms < 15_000 < booted.time_boot_ms
