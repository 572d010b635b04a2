"""The simulator's other vehicles: an ArduRover ground vehicle, and the quadcopter playing
PX4 on the wire. Logic stepped directly; identity checked over TCP through mavutil, the
way the agent reads it."""

from __future__ import annotations

import math
from collections.abc import Callable

import pytest
from pymavlink import mavutil
from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from simulator import DEFAULT_HOME, Copter, CopterMode, LocalFrame, MavResult, main
from simulator.config import parse_args
from simulator.mavconst import (
    LandedState,
    MavAutopilot,
    MavCmd,
    MavFrame,
    MavState,
    MavType,
    MissionState,
    ModeFlag,
    Px4AutoMode,
    Px4MainMode,
    RoverMode,
)
from simulator.mavlink.telemetry import TelemetryBuilder
from simulator.personality.px4 import Px4Personality
from simulator.rover import Rover
from simulator.vehicle import ItemReached
from simulator.vehicle.stored_mission import MissionItem
from tests.support.copters import run_until, texts
from tests.support.simulators import command, mavlink_client, simulator_process, wait_for
from vehicle_agents.fcu import dialect as mavlink_dialect  # noqa: F401  (decodes AVAILABLE_MODES)

# Degrees per metre north and east of home.
_FRAME = LocalFrame(DEFAULT_HOME.lat, DEFAULT_HOME.lon, DEFAULT_HOME.alt)
NORTH = _FRAME.to_geo(0.0, 1.0)[0] - DEFAULT_HOME.lat
EAST = _FRAME.to_geo(1.0, 0.0)[1] - DEFAULT_HOME.lon


def waypoint(seq: int, north: float, east: float, hold_s: float = 0.0) -> MissionItem:
    return MissionItem(
        seq,
        MavFrame.GLOBAL_RELATIVE_ALT,
        MavCmd.NAV_WAYPOINT,
        hold_s,
        x=round((DEFAULT_HOME.lat + north * NORTH) * 1e7),
        y=round((DEFAULT_HOME.lon + east * EAST) * 1e7),
    )


def mode_name(vehicle: Copter | Rover) -> str:
    return str(mavutil.mode_string_v10(TelemetryBuilder(vehicle, 0.0).heartbeat()))


def test_new_enums_match_pymavlink() -> None:
    for mode in RoverMode:  # the names the agent shows come from this table
        assert mavutil.mode_mapping_rover[mode.value] == mode.name
    for main_mode in Px4MainMode:
        assert getattr(mavutil, f"PX4_CUSTOM_MAIN_MODE_{main_mode.name}") == main_mode.value
    for sub_mode in Px4AutoMode:
        if sub_mode.name not in ("PRECLAND", "VTOL_TAKEOFF"):  # newer than pymavlink
            assert getattr(mavutil, f"PX4_CUSTOM_SUB_MODE_AUTO_{sub_mode.name}") == sub_mode
    for mav_type in MavType:
        assert getattr(mavlink2, f"MAV_TYPE_{mav_type.name}") == mav_type.value
    for autopilot in MavAutopilot:
        assert getattr(mavlink2, f"MAV_AUTOPILOT_{autopilot.name}") == autopilot.value


# -- ArduRover -----------------------------------------------------------------------------


def test_rover_identifies_itself_and_boots_in_manual() -> None:
    rover = Rover(DEFAULT_HOME)
    heartbeat = TelemetryBuilder(rover, 0.0).heartbeat()
    assert heartbeat.type == mavlink2.MAV_TYPE_GROUND_ROVER
    assert heartbeat.autopilot == mavlink2.MAV_AUTOPILOT_ARDUPILOTMEGA
    assert mode_name(rover) == "MANUAL"
    assert heartbeat.base_mode == ModeFlag.CUSTOM_MODE_ENABLED | ModeFlag.MANUAL_INPUT_ENABLED
    assert rover.system_status() is MavState.ACTIVE  # Rover: STANDBY only in HOLD
    rover.set_mode(RoverMode.HOLD)
    assert rover.system_status() is MavState.STANDBY
    assert rover.landed_state() is LandedState.UNDEFINED
    names = rover.param_table.names()
    assert "WP_SPEED" in names
    assert "WPNAV_SPEED" not in names
    assert rover.param_table.get("WP_SPEED") == 2.0


def test_rover_has_no_takeoff_or_land_and_disarms_at_any_time() -> None:
    rover = Rover(DEFAULT_HOME)
    assert rover.nav_takeoff(10.0, MavFrame.GLOBAL_RELATIVE_ALT) is MavResult.UNSUPPORTED
    assert rover.nav_land() is MavResult.UNSUPPORTED
    rover.set_mode(RoverMode.GUIDED)
    assert rover.arm() is MavResult.ACCEPTED
    assert texts(rover) == ["Throttle armed"]
    here = rover.position()
    rover.guided_goto(here.lat + 50 * NORTH, here.lon, 0.0)
    rover.advance(5.0)
    assert rover.body.groundspeed > 1.0
    assert rover.disarm() is MavResult.ACCEPTED  # no "in flight" on the ground


def test_rover_drives_a_mission_on_the_ground() -> None:
    rover = Rover(DEFAULT_HOME)
    assert rover.set_mode(RoverMode.AUTO) is MavResult.FAILED  # no mission yet
    assert texts(rover) == ["No Mission. Can't set AUTO.", "Flight mode change failed"]
    rover.set_mission(
        [
            MissionItem(0, MavFrame.GLOBAL, MavCmd.NAV_WAYPOINT),
            MissionItem(1, MavFrame.GLOBAL_RELATIVE_ALT, MavCmd.NAV_TAKEOFF, z=10.0),
            waypoint(2, 30.0, 0.0),
            MissionItem(3, MavFrame.MISSION, MavCmd.DO_CHANGE_SPEED, 1.0, 3.0),
            waypoint(4, 30.0, 30.0, hold_s=2.0),
            MissionItem(5, MavFrame.GLOBAL_RELATIVE_ALT, MavCmd.NAV_RETURN_TO_LAUNCH),
        ]
    )
    assert rover.set_mode(RoverMode.AUTO) is MavResult.ACCEPTED
    assert rover.arm() is MavResult.ACCEPTED  # Rover arms in AUTO
    reached: list[int] = []
    said: list[str] = []
    top_speed = 0.0

    def finished(vehicle: Rover) -> bool:
        nonlocal top_speed
        reached.extend(e.seq for e in vehicle.drain_events() if isinstance(e, ItemReached))
        said.extend(texts(vehicle))
        top_speed = max(top_speed, vehicle.body.groundspeed)
        assert vehicle.body.alt == 0.0  # on the ground all the way
        return vehicle.mission_state() is MissionState.COMPLETE

    run_until(rover, finished, 120)
    assert reached == [1, 2, 4, 5]
    assert "Skipping invalid cmd #22" in said  # NAV_TAKEOFF is not a Rover command
    assert "Reached waypoint #2" in said
    assert "speed: 3.0 m/s" in said
    assert said[-1] == "Mission Complete"
    assert top_speed == pytest.approx(3.0, abs=0.01)
    assert rover.mode is RoverMode.AUTO  # MIS_DONE_BEHAVE 0: stopped, still in AUTO
    assert rover.armed
    assert math.hypot(rover.body.north, rover.body.east) < rover.params.wpnav_radius + 0.5


def test_rover_change_speed_and_rtl() -> None:
    rover = Rover(DEFAULT_HOME)
    rover.set_mode(RoverMode.GUIDED)
    rover.arm()
    assert rover.change_speed(2, 1.0) is MavResult.DENIED  # no climb speed on wheels
    assert rover.change_speed(1, 4.0) is MavResult.ACCEPTED
    rover.guided_goto(DEFAULT_HOME.lat + 100 * NORTH, DEFAULT_HOME.lon, 0.0)
    rover.advance(15.0)
    assert rover.body.groundspeed == pytest.approx(4.0, abs=0.01)
    assert rover.return_to_launch() is MavResult.ACCEPTED
    said: list[str] = []

    def home_and_stopped(vehicle: Rover) -> bool:
        said.extend(texts(vehicle))
        near = math.hypot(vehicle.body.north, vehicle.body.east) < vehicle.params.wpnav_radius
        return near and vehicle.body.groundspeed < 0.01

    run_until(rover, home_and_stopped, 120)
    assert "Reached destination" in said
    rover.set_mode(RoverMode.HOLD)
    assert rover.change_speed(1, 2.0) is MavResult.FAILED


# -- the quad playing PX4 ----------------------------------------------------------------


def px4() -> Copter:
    return Copter(DEFAULT_HOME, personality=Px4Personality())


def test_px4_encodes_main_and_sub_modes_as_pymavlink_decodes_them() -> None:
    copter = px4()
    heartbeat = TelemetryBuilder(copter, 0.0).heartbeat()
    assert heartbeat.autopilot == mavlink2.MAV_AUTOPILOT_PX4
    assert mode_name(copter) == "MANUAL"
    for name, (base, main_mode, sub_mode) in mavutil.px4_map.items():
        if name in ("MANUAL", "POSCTL", "LOITER", "MISSION", "RTL", "LAND"):
            assert copter.request_mode(base, main_mode, sub_mode) is MavResult.ACCEPTED
            assert mode_name(copter) == name
    # SET_MODE carries the mode encoded as HEARTBEAT's custom_mode
    assert copter.request_mode_encoded(1, (4 << 16) | (4 << 24)) is MavResult.ACCEPTED
    assert mode_name(copter) == "MISSION"
    assert copter.mode is CopterMode.AUTO


def test_px4_reports_no_mission_as_px4_does() -> None:
    """MISSION_CURRENT.total is UINT16_MAX without a mission (mavlink_mission.cpp)."""
    current = TelemetryBuilder(px4(), 0.0).mission_current()
    assert (current.seq, current.total) == (0, 65535)
    assert TelemetryBuilder(Copter(DEFAULT_HOME), 0.0).mission_current().total == 0


def test_px4_declines_as_px4_does() -> None:
    copter = px4()
    before = copter.custom_mode()
    # OFFBOARD with no setpoint stream: Commander takes it, and the vehicle stays put.
    assert copter.request_mode(1, 6, 0) is MavResult.ACCEPTED
    assert copter.custom_mode() == before
    assert copter.request_mode(1, 4, 42) is MavResult.TEMPORARILY_REJECTED
    assert texts(copter) == ["Unsupported auto mode"]
    copter.request_mode(1, 4, 5)  # AUTO.RTL
    assert copter.arm() is MavResult.TEMPORARILY_REJECTED


def test_px4_takeoff_is_above_sea_level_then_holds() -> None:
    copter = px4()
    assert copter.arm() is MavResult.ACCEPTED
    takeoff = copter.nav_takeoff(DEFAULT_HOME.alt + 12.0, MavFrame.GLOBAL)
    assert takeoff is MavResult.ACCEPTED
    assert mode_name(copter) == "TAKEOFF"
    run_until(copter, lambda c: not c.taking_off, 60)
    assert copter.relative_alt == pytest.approx(12.0, abs=0.2)
    assert mode_name(copter) == "LOITER"  # Takeoff hands over to Hold
    assert copter.system_status() is MavState.ACTIVE  # PX4: armed is ACTIVE
    assert copter.disarm() is MavResult.TEMPORARILY_REJECTED
    assert texts(copter)[-1] == "Disarming denied: not landed"
    assert copter.request_mode(1, 4, 6) is MavResult.ACCEPTED  # AUTO.LAND
    run_until(copter, lambda c: not c.armed, 120)


def takeoff_away(north: float) -> list[MissionItem]:
    """Home, a take-off to 10 m whose position is ``north`` metres north of home, RTL."""
    takeoff = waypoint(1, north, 0.0)
    return [
        MissionItem(0, MavFrame.GLOBAL, MavCmd.NAV_WAYPOINT),
        MissionItem(1, takeoff.frame, MavCmd.NAV_TAKEOFF, x=takeoff.x, y=takeoff.y, z=10.0),
        MissionItem(2, MavFrame.GLOBAL_RELATIVE_ALT, MavCmd.NAV_RETURN_TO_LAUNCH),
    ]


@pytest.mark.parametrize(
    ("make", "flies_there"), [(px4, True), (lambda: Copter(DEFAULT_HOME), False)]
)
def test_a_mission_take_off_climbs_then_px4_flies_to_its_position(
    make: Callable[[], Copter], flies_there: bool
) -> None:
    """PX4's Mission arms only when asked; armed, it climbs where it stands, then flies to
    the take-off item's position before the next item. ArduCopter climbs and goes on."""
    copter = make()
    copter.set_mission(takeoff_away(30.0))
    if flies_there:
        assert copter.request_mode(*mavutil.px4_map["MISSION"]) is MavResult.ACCEPTED
        copter.advance(5.0)
        assert not copter.armed, "PX4 does not arm itself in Mission"
        assert copter.arm() is MavResult.ACCEPTED
    else:
        copter.set_mode(CopterMode.GUIDED)
        copter.arm()
        assert copter.set_mode(CopterMode.AUTO) is MavResult.ACCEPTED
    run_until(copter, lambda c: c.relative_alt > 9.5, 60)
    assert math.hypot(copter.body.north, copter.body.east) < 1.0, "climbs where it stands"
    run_until(copter, lambda c: c.mission_current == 2, 60)
    assert copter.body.north == pytest.approx(30.0 if flies_there else 0.0, abs=2.5)
    assert copter.relative_alt == pytest.approx(10.0, abs=1.0)


# -- over TCP, and on the command line -----------------------------------------------------


def test_rover_process_over_tcp() -> None:
    with (
        simulator_process("--frame", "rover", "--speedup", "10") as (port, _lines),
        mavlink_client(f"tcp:127.0.0.1:{port}") as gcs,
    ):
        heartbeat = wait_for(gcs, ["HEARTBEAT"], lambda m: True, 10, "a heartbeat")
        assert heartbeat.type == mavlink2.MAV_TYPE_GROUND_ROVER
        assert mavutil.mode_string_v10(heartbeat) == "MANUAL"
        assert command(gcs, mavlink2.MAV_CMD_NAV_TAKEOFF, 0, 0, 0, 0, 0, 0, 10) == 3
        assert command(gcs, mavlink2.MAV_CMD_DO_SET_MODE, 1, RoverMode.HOLD) == 0
        wait_for(gcs, ["HEARTBEAT"], lambda m: mavutil.mode_string_v10(m) == "HOLD", 5, "HOLD")


def test_px4_process_over_tcp() -> None:
    with (
        simulator_process("--autopilot", "px4", "--speedup", "10") as (port, _lines),
        mavlink_client(f"tcp:127.0.0.1:{port}") as gcs,
    ):
        heartbeat = wait_for(gcs, ["HEARTBEAT"], lambda m: True, 10, "a heartbeat")
        assert heartbeat.autopilot == mavlink2.MAV_AUTOPILOT_PX4
        base, main_mode, sub_mode = mavutil.px4_map["POSCTL"]
        assert command(gcs, mavlink2.MAV_CMD_DO_SET_MODE, base, main_mode, sub_mode) == 0
        # PX4 sends CURRENT_MODE on each change (at once), and lists its modes when asked.
        current = wait_for(gcs, ["CURRENT_MODE"], lambda m: True, 5, "CURRENT_MODE")
        assert (current.custom_mode, current.standard_mode) == (main_mode << 16, 1)
        wait_for(gcs, ["HEARTBEAT"], lambda m: mavutil.mode_string_v10(m) == "POSCTL", 5, "POSCTL")
        assert command(gcs, mavlink2.MAV_CMD_REQUEST_MESSAGE, 435, 0) == 0
        listed = [wait_for(gcs, ["AVAILABLE_MODES"], lambda m: True, 5, "a mode")]
        while len(listed) < listed[0].number_modes:
            listed.append(wait_for(gcs, ["AVAILABLE_MODES"], lambda m: True, 5, "a mode"))
        assert [m.mode_index for m in listed] == list(range(1, len(listed) + 1))
        names = {m.mode_name for m in listed}
        assert {"Manual", "Hold", "Offboard", "Precision Landing"} <= names
        hidden = [m for m in listed if m.properties & 2]  # NOT_USER_SELECTABLE
        assert {m.mode_name for m in hidden} == {"Termination", "(Mode not available)"}
        assert len(hidden) == 9
        assert not any(m.custom_mode >> 16 & 0xFF == 8 for m in listed)  # no RATTITUDE


def test_frame_and_autopilot_options() -> None:
    assert parse_args([]).frame == "quad"
    assert parse_args([]).autopilot == "ardupilot"
    assert parse_args(["--frame", "rover"]).frame == "rover"
    assert parse_args(["--autopilot", "px4"]).autopilot == "px4"
    assert main(["--frame", "rover", "--autopilot", "px4"]) == 2  # PX4 rovers: not simulated
    assert main(["--frame", "plane"]) == 2
