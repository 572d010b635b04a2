"""MAVLink in, replies out: the simulator's message handling and telemetry, without sockets."""

from __future__ import annotations

import math

import pytest
from pymavlink.dialects.v20 import ardupilotmega as mavlink2
from pymavlink.dialects.v20 import development

from simulator import DEFAULT_HOME
from simulator.mavconst import (
    FORCE_ARM_MAGIC,
    FORCE_DISARM_MAGIC,
    CopterMode,
    LandedState,
    MavCmd,
    MavFrame,
    MavResult,
    MavState,
    ModeFlag,
    MsgId,
    Severity,
    SysSensor,
)
from simulator.mavlink.commands import Reply
from simulator.mavlink.telemetry import DEFAULT_RATES_HZ
from tests.support.copters import GCS_COMPID, GCS_SYSID, SYSID, Vehicle, ack_of, kinds


def test_enums_match_pymavlink() -> None:
    for enum, prefix in [
        (MavResult, "MAV_RESULT_"),
        (Severity, "MAV_SEVERITY_"),
        (MavState, "MAV_STATE_"),
        (LandedState, "MAV_LANDED_STATE_"),
        (ModeFlag, "MAV_MODE_FLAG_"),
        (MavFrame, "MAV_FRAME_"),
        (MavCmd, "MAV_CMD_"),
        (SysSensor, "MAV_SYS_STATUS_"),
    ]:
        for member in enum:
            if member is MavResult.COMMAND_UNSUPPORTED_MAV_FRAME:
                continue  # pymavlink's dialect ends MAV_RESULT at 8 (9 is its ENUM_END)
            assert getattr(mavlink2, prefix + str(member.name)) == member.value, member
    assert MavResult.COMMAND_UNSUPPORTED_MAV_FRAME == 9  # common.xml
    for msg in MsgId:
        # The standard-modes messages are in pymavlink's development dialect only
        dialect = development if msg in (MsgId.AVAILABLE_MODES, MsgId.CURRENT_MODE) else mavlink2
        assert getattr(dialect, f"MAVLINK_MSG_ID_{msg.name}") == msg.value
    for mode in CopterMode:
        assert mavlink2.enums["COPTER_MODE"][mode.value].name == f"COPTER_MODE_{mode.name}"
    assert FORCE_DISARM_MAGIC == 21196.0
    assert FORCE_ARM_MAGIC == 2989.0


def test_arm_is_acknowledged_to_the_sender_after_the_statustext() -> None:
    vehicle = Vehicle()
    vehicle.copter.set_mode(CopterMode.GUIDED)
    replies = vehicle.command(MavCmd.COMPONENT_ARM_DISARM, 1)
    assert kinds(replies) == ["STATUSTEXT", "COMMAND_ACK"]
    text, ack = replies
    assert not text.to_sender_only  # STATUSTEXT goes to every client
    assert text.message.text == "Arming motors"
    assert ack.to_sender_only
    assert (ack.message.command, ack.message.result) == (MavCmd.COMPONENT_ARM_DISARM, 0)
    assert (ack.message.target_system, ack.message.target_component) == (GCS_SYSID, GCS_COMPID)
    assert vehicle.copter.armed


def test_refused_arm_explains_itself() -> None:
    vehicle = Vehicle()
    vehicle.copter.set_mode(CopterMode.LAND)
    replies = vehicle.command(MavCmd.COMPONENT_ARM_DISARM, 1)
    assert kinds(replies) == ["STATUSTEXT", "COMMAND_ACK"]
    assert replies[0].message.severity == mavlink2.MAV_SEVERITY_CRITICAL
    assert replies[0].message.text == "Arm: LAND mode not armable"
    assert ack_of(replies).result == mavlink2.MAV_RESULT_FAILED


def test_force_flags() -> None:
    vehicle = Vehicle()
    vehicle.copter.set_mode(CopterMode.RTL)
    assert ack_of(vehicle.command(MavCmd.COMPONENT_ARM_DISARM, 1, 21196)).result == 4
    assert ack_of(vehicle.command(MavCmd.COMPONENT_ARM_DISARM, 1, 2989)).result == 0
    flying = Vehicle()
    flying.fly()
    assert ack_of(flying.command(MavCmd.COMPONENT_ARM_DISARM, 0)).result == 4
    assert flying.copter.armed
    assert ack_of(flying.command(MavCmd.COMPONENT_ARM_DISARM, 0, 21196)).result == 0
    assert not flying.copter.armed
    assert ack_of(flying.command(MavCmd.COMPONENT_ARM_DISARM, 2)).result == 3


def test_commands_for_another_system_are_ignored() -> None:
    vehicle = Vehicle()
    assert vehicle.command(MavCmd.COMPONENT_ARM_DISARM, 1, target=SYSID + 1) == []
    assert not vehicle.copter.armed
    # target 0 is a broadcast
    assert ack_of(vehicle.command(MavCmd.COMPONENT_ARM_DISARM, 1, target=0)).result == 0


def test_unsupported_command() -> None:
    ack = ack_of(Vehicle().command(mavlink2.MAV_CMD_DO_SET_SERVO, 5, 1500))
    assert ack.result == mavlink2.MAV_RESULT_UNSUPPORTED


def test_set_mode_command_and_legacy_message() -> None:
    vehicle = Vehicle()
    custom = mavlink2.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED
    assert ack_of(vehicle.command(MavCmd.DO_SET_MODE, custom, 4)).result == 0
    assert vehicle.mode() is CopterMode.GUIDED
    assert ack_of(vehicle.command(MavCmd.DO_SET_MODE, 0, 5)).result == 2  # no custom flag
    replies = vehicle.command(MavCmd.DO_SET_MODE, custom, 42)
    assert ack_of(replies).result == 4
    assert replies[0].message.text == "No such mode 42"
    # SET_MODE is acknowledged as "command" 11, as ArduPilot does
    replies = vehicle.send(mavlink2.MAVLink_set_mode_message(SYSID, custom, 9))
    assert (ack_of(replies).command, ack_of(replies).result) == (11, 0)
    assert vehicle.mode() is CopterMode.LAND


def test_auto_without_mission_refused_in_flight() -> None:
    vehicle = Vehicle()
    vehicle.fly()
    replies = vehicle.command(MavCmd.DO_SET_MODE, 1, 3)
    assert ack_of(replies).result == mavlink2.MAV_RESULT_FAILED
    assert replies[0].message.text == "Mode change to AUTO failed: init failed"


def test_takeoff_land_and_rtl_commands() -> None:
    vehicle = Vehicle()
    assert ack_of(vehicle.command(MavCmd.NAV_TAKEOFF, 0, 0, 0, 0, 0, 0, 10)).result == 4
    vehicle.copter.set_mode(CopterMode.GUIDED)
    vehicle.command(MavCmd.COMPONENT_ARM_DISARM, 1)
    assert ack_of(vehicle.command(MavCmd.NAV_TAKEOFF, 0, 0, 0, 0, 0, 0, 10)).result == 0
    vehicle.copter.advance(20.0)
    assert vehicle.copter.relative_alt == pytest.approx(10.0, abs=0.1)
    assert ack_of(vehicle.command(MavCmd.NAV_RETURN_TO_LAUNCH)).result == 0
    assert vehicle.mode() is CopterMode.RTL
    assert ack_of(vehicle.command(MavCmd.NAV_LAND)).result == 0
    assert vehicle.mode() is CopterMode.LAND


def test_takeoff_as_command_int_needs_a_relative_frame() -> None:
    vehicle = Vehicle()
    vehicle.copter.set_mode(CopterMode.GUIDED)
    vehicle.copter.arm()
    ack = ack_of(vehicle.command_int(MavCmd.NAV_TAKEOFF, MavFrame.GLOBAL, [], 0, 0, 10.0))
    assert ack.result == mavlink2.MAV_RESULT_DENIED
    frame = MavFrame.GLOBAL_RELATIVE_ALT_INT
    ack = ack_of(vehicle.command_int(MavCmd.NAV_TAKEOFF, frame, [], 0, 0, 10.0))
    assert ack.result == mavlink2.MAV_RESULT_ACCEPTED


def test_do_reposition_in_guided() -> None:
    vehicle = Vehicle()
    vehicle.fly()
    target = vehicle.copter.geo_of(north=40.0, east=-30.0)
    lat, lon = round(target.lat * 1e7), round(target.lon * 1e7)
    frame = MavFrame.GLOBAL_RELATIVE_ALT_INT
    ack = ack_of(
        vehicle.command_int(MavCmd.DO_REPOSITION, frame, [-1, 0, 0, math.nan], lat, lon, 15)
    )
    assert ack.result == mavlink2.MAV_RESULT_ACCEPTED
    assert vehicle.copter.guided_target == pytest.approx((40.0, -30.0, 15.0), abs=0.01)
    vehicle.copter.advance(30.0)
    point = vehicle.copter.position()
    assert (round(point.lat * 1e7), round(point.lon * 1e7)) == (lat, lon)
    assert vehicle.copter.relative_alt == pytest.approx(15.0, abs=0.01)


def test_do_reposition_absolute_altitude_and_mode_change() -> None:
    vehicle = Vehicle()
    vehicle.fly()
    vehicle.copter.set_mode(CopterMode.LOITER)
    home = DEFAULT_HOME
    lat, lon = round(home.lat * 1e7), round(home.lon * 1e7)
    params = [-1.0, 0.0, 0.0, 0.0]
    ack = ack_of(
        vehicle.command_int(MavCmd.DO_REPOSITION, MavFrame.GLOBAL_INT, params, lat, lon, 600)
    )
    assert ack.result == mavlink2.MAV_RESULT_DENIED  # not in GUIDED, no change-mode flag
    params[1] = mavlink2.MAV_DO_REPOSITION_FLAGS_CHANGE_MODE
    ack = ack_of(
        vehicle.command_int(MavCmd.DO_REPOSITION, MavFrame.GLOBAL_INT, params, lat, lon, 600)
    )
    assert ack.result == mavlink2.MAV_RESULT_ACCEPTED
    assert vehicle.mode() is CopterMode.GUIDED
    assert vehicle.copter.guided_target == pytest.approx((0.0, 0.0, 16.0), abs=0.01)  # MSL


def test_do_reposition_as_command_long_is_relative() -> None:
    vehicle = Vehicle()
    vehicle.fly()
    target = vehicle.copter.geo_of(north=10.0, east=10.0)
    ack = ack_of(vehicle.command(MavCmd.DO_REPOSITION, -1, 0, 0, 0, target.lat, target.lon, 12.0))
    assert ack.result == mavlink2.MAV_RESULT_ACCEPTED
    # float32 degrees resolve about a metre at this longitude: why COMMAND_INT exists
    assert vehicle.copter.guided_target == pytest.approx((10.0, 10.0, 12.0), abs=1.5)


def test_set_position_target_global_int() -> None:
    vehicle = Vehicle()
    target = vehicle.copter.geo_of(north=25.0, east=5.0)
    lat, lon = round(target.lat * 1e7), round(target.lon * 1e7)

    def position_target(frame: int) -> list[Reply]:
        return vehicle.send(
            mavlink2.MAVLink_set_position_target_global_int_message(
                0, SYSID, 1, frame, 0b110111111000, lat, lon, 8.0, 0, 0, 0, 0, 0, 0, 0, 0
            )
        )

    vehicle.copter.set_mode(CopterMode.LOITER)
    assert position_target(MavFrame.GLOBAL_RELATIVE_ALT_INT) == []  # ignored outside GUIDED
    vehicle.fly()
    assert position_target(MavFrame.GLOBAL_TERRAIN_ALT_INT) == []  # no ack exists for it
    assert vehicle.copter.guided_target == pytest.approx((25.0, 5.0, 8.0), abs=0.01)
    vehicle.copter.advance(20.0)
    assert vehicle.copter.relative_alt == pytest.approx(8.0, abs=0.01)
    position_target(MavFrame.LOCAL_NED)  # unsupported frame: stop and hold
    assert vehicle.copter.guided_target == pytest.approx((25.0, 5.0, 8.0), abs=0.01)


def test_request_message_answers_ack_then_message() -> None:
    vehicle = Vehicle()
    replies = vehicle.command(MavCmd.REQUEST_MESSAGE, MsgId.HOME_POSITION)
    assert kinds(replies) == ["COMMAND_ACK", "HOME_POSITION"]
    assert all(r.to_sender_only for r in replies)
    home = replies[1].message
    assert (home.latitude, home.longitude, home.altitude) == (-353632620, 1491652370, 584000)
    for msg_id in (MsgId.AUTOPILOT_VERSION, MsgId.GPS_GLOBAL_ORIGIN, MsgId.SYS_STATUS):
        replies = vehicle.command(MavCmd.REQUEST_MESSAGE, msg_id)
        assert replies[1].message.get_msgId() == msg_id
    assert ack_of(vehicle.command(MavCmd.REQUEST_MESSAGE, 9999)).result == 4


def test_get_home_position_and_capabilities() -> None:
    vehicle = Vehicle()
    assert kinds(vehicle.command(MavCmd.GET_HOME_POSITION)) == ["HOME_POSITION", "COMMAND_ACK"]
    replies = vehicle.command(MavCmd.REQUEST_AUTOPILOT_CAPABILITIES, 1)
    assert kinds(replies) == ["COMMAND_ACK", "AUTOPILOT_VERSION"]
    version = replies[1].message
    assert version.capabilities & mavlink2.MAV_PROTOCOL_CAPABILITY_MAVLINK2
    assert version.flight_sw_version >> 24 == 4


def test_message_intervals() -> None:
    vehicle = Vehicle()
    position = MsgId.GLOBAL_POSITION_INT
    assert ack_of(vehicle.command(MavCmd.SET_MESSAGE_INTERVAL, position, 500_000)).result == 0
    assert vehicle.streams.interval(position) == 0.5
    replies = vehicle.command(MavCmd.GET_MESSAGE_INTERVAL, position)
    assert replies[-1].message.interval_us == 500_000
    vehicle.command(MavCmd.SET_MESSAGE_INTERVAL, position, -1)
    assert vehicle.streams.interval(position) is None
    vehicle.command(MavCmd.SET_MESSAGE_INTERVAL, position, 0)
    assert vehicle.streams.interval(position) == pytest.approx(0.1)
    assert ack_of(vehicle.command(MavCmd.SET_MESSAGE_INTERVAL, 9999, 1000)).result == 2
    # REQUEST_DATA_STREAM is accepted silently (no ack exists for it)
    request = mavlink2.MAVLink_request_data_stream_message(SYSID, 1, 0, 10, 1)
    assert vehicle.send(request) == []


def test_do_change_speed_in_guided() -> None:
    vehicle = Vehicle()
    assert ack_of(vehicle.command(MavCmd.DO_CHANGE_SPEED, 1, 3.0)).result == 4
    vehicle.fly()
    assert ack_of(vehicle.command(MavCmd.DO_CHANGE_SPEED, 1, 3.0)).result == 0
    target = vehicle.copter.geo_of(north=100.0, east=0.0)
    vehicle.copter.guided_goto(target.lat, target.lon, 10.0)
    vehicle.copter.advance(10.0)
    assert vehicle.copter.body.groundspeed == pytest.approx(3.0, abs=0.01)


def test_telemetry_reflects_the_state() -> None:
    vehicle = Vehicle()
    vehicle.fly(10.0)
    telemetry = vehicle.telemetry
    heartbeat = telemetry.heartbeat()
    assert heartbeat.type == mavlink2.MAV_TYPE_QUADROTOR
    assert heartbeat.autopilot == mavlink2.MAV_AUTOPILOT_ARDUPILOTMEGA
    assert heartbeat.custom_mode == 4
    assert heartbeat.base_mode == 217  # custom | stabilize | guided | manual input | armed
    assert heartbeat.system_status == mavlink2.MAV_STATE_ACTIVE

    position = telemetry.global_position_int()
    assert position.relative_alt == pytest.approx(10_000, abs=50)
    assert position.alt == pytest.approx(594_000, abs=50)
    assert (position.lat, position.lon) == (-353632620, 1491652370)
    assert position.time_boot_ms == round(vehicle.copter.time_s * 1000)
    assert 0 <= position.hdg < 36000

    gps = telemetry.gps_raw_int()
    assert (gps.fix_type, gps.satellites_visible) == (3, 10)
    assert gps.eph < 200
    status = telemetry.sys_status()
    assert status.onboard_control_sensors_health & SysSensor.SENSOR_GPS
    assert status.onboard_control_sensors_health & SysSensor.PREARM_CHECK
    assert 14_000 < status.voltage_battery < 16_800
    assert status.current_battery == pytest.approx(1500, abs=60)
    assert 0 < status.battery_remaining <= 100
    hud = telemetry.vfr_hud()
    assert hud.alt == pytest.approx(594.0, abs=0.05)
    assert hud.throttle == pytest.approx(35, abs=1)
    battery = telemetry.battery_status()
    assert battery.voltages[0] == status.voltage_battery
    assert battery.current_consumed > 0
    assert telemetry.extended_sys_state().landed_state == mavlink2.MAV_LANDED_STATE_IN_AIR


def test_no_gps_shows_in_telemetry() -> None:
    vehicle = Vehicle()
    vehicle.copter.set_mode(CopterMode.GUIDED)
    vehicle.copter.set_gps_fix(1)
    assert vehicle.telemetry.gps_raw_int().fix_type == 1
    health = vehicle.telemetry.sys_status().onboard_control_sensors_health
    assert not health & SysSensor.SENSOR_GPS
    assert not health & SysSensor.PREARM_CHECK


def test_every_streamed_message_encodes() -> None:
    vehicle = Vehicle()
    vehicle.fly()
    encoder = mavlink2.MAVLink(None, srcSystem=SYSID, srcComponent=1)
    parser = mavlink2.MAVLink(None)
    for msg_id in sorted(vehicle.telemetry.supported):
        message = vehicle.telemetry.build(msg_id)
        assert message is not None
        frame = message.pack(encoder)
        assert frame[0] == 0xFD  # MAVLink 2
        [decoded] = parser.parse_buffer(frame)
        assert decoded.get_msgId() == msg_id
        assert decoded.get_srcSystem() == SYSID
    assert set(DEFAULT_RATES_HZ) <= vehicle.telemetry.supported


def test_timesync_requests_get_the_boards_nanoseconds_since_boot() -> None:
    vehicle = Vehicle()
    vehicle.copter.advance(12.5)
    [reply] = vehicle.send(mavlink2.MAVLink_timesync_message(0, 987_654_321))
    assert reply.to_sender_only
    assert reply.message.get_type() == "TIMESYNC"
    assert reply.message.ts1 == 987_654_321
    assert reply.message.tc1 == pytest.approx(vehicle.copter.time_s * 1e9, abs=1e3)
    assert vehicle.send(mavlink2.MAVLink_timesync_message(5, 6)) == []  # an answer, not ours
