"""Which items the simulated ArduPilot stores, by frame: AP_Mission checks the frame only of
commands that store a location (stored_in_location)."""

from __future__ import annotations

from simulator.mavconst import MavCmd, MavFrame
from simulator.vehicle.stored_mission import MissionItem, check_item


def test_rtl_in_the_mission_frame_is_stored_as_qgc_writes_it() -> None:
    assert check_item(MissionItem(3, MavFrame.MISSION, MavCmd.NAV_RETURN_TO_LAUNCH)) is None


def test_a_waypoint_without_a_global_frame_is_refused() -> None:
    assert check_item(MissionItem(3, MavFrame.MISSION, MavCmd.NAV_WAYPOINT)) == "frame"


def test_camera_commands_are_stored() -> None:
    for command in (MavCmd.DO_SET_CAM_TRIGG_DIST, MavCmd.DO_DIGICAM_CONTROL):
        assert check_item(MissionItem(2, MavFrame.MISSION, command)) is None
