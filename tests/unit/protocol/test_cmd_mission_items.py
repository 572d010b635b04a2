"""Mission items checked against what their MAV_CMD needs, before anything is sent."""

from __future__ import annotations

import pytest
from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from protocol.messages import MissionItem
from protocol.mission_rules import mission_problems

TAKEOFF = mavlink2.MAV_CMD_NAV_TAKEOFF
WAYPOINT = mavlink2.MAV_CMD_NAV_WAYPOINT
LOITER_TIME = mavlink2.MAV_CMD_NAV_LOITER_TIME
LOITER_TURNS = mavlink2.MAV_CMD_NAV_LOITER_TURNS
LAND = mavlink2.MAV_CMD_NAV_LAND
RTL = mavlink2.MAV_CMD_NAV_RETURN_TO_LAUNCH
CHANGE_SPEED = mavlink2.MAV_CMD_DO_CHANGE_SPEED
JUMP = mavlink2.MAV_CMD_DO_JUMP
DELAY = mavlink2.MAV_CMD_CONDITION_DELAY
CAM_TRIGG_DIST = mavlink2.MAV_CMD_DO_SET_CAM_TRIGG_DIST
HERE = {"lat": -35.36, "lon": 149.16}


def item(command: int, **fields: float) -> MissionItem:
    return MissionItem(command=command, **fields)  # type: ignore[arg-type]


def test_a_good_mission_has_no_problems() -> None:
    items = [
        item(TAKEOFF, alt=10),
        item(CHANGE_SPEED, param1=1, param2=3),
        item(WAYPOINT, param1=2, alt=10, **HERE),
        item(LOITER_TIME, param1=5, **HERE),
        item(JUMP, param1=3, param2=2),
        item(LAND),  # ArduPilot lands where it is when no position is given
        item(RTL),
    ]
    assert mission_problems(items) == []


def test_each_problem_names_its_item_and_command() -> None:
    problems = mission_problems(
        [item(TAKEOFF, alt=10), item(WAYPOINT, alt=10), item(LOITER_TIME, param1=-1, **HERE)]
    )
    assert problems == [
        "item 2 (NAV_WAYPOINT): latitude and longitude are 0, 0: not a place to go "
        "(give its position)",
        "item 3 (NAV_LOITER_TIME): loiter time -1 s is negative",
    ]


@pytest.mark.parametrize(
    ("bad", "complaint"),
    [
        (item(WAYPOINT, frame=1, **HERE), "MAV_FRAME_LOCAL_NED is not a global frame"),
        (item(WAYPOINT, frame=2, **HERE), "MAV_FRAME_MISSION is not a global frame"),
        (item(WAYPOINT, param1=-3, **HERE), "hold time -3 s is negative"),
        (item(WAYPOINT, param2=-1, **HERE), "acceptance radius -1 m is negative"),
        (item(LOITER_TURNS, param1=0, **HERE), "0 turns"),
        (item(TAKEOFF, alt=0), "take-off altitude 0 m is not above home"),
        (item(CHANGE_SPEED, param1=1, param2=0), "speed 0 m/s: a speed must be above 0"),
        (item(CHANGE_SPEED, param1=1, param2=-5), "speed -5 m/s"),
        (item(CHANGE_SPEED, param1=7, param2=3), "speed type 7 is not 0"),
        (item(DELAY, param1=-2), "delay -2 s is negative"),
        (item(CAM_TRIGG_DIST, param1=-10), "trigger distance -10 m is negative"),
        (item(JUMP, param1=9, param2=1), "jump target 9 is not an item of this mission (1..1)"),
        (item(JUMP, param1=1, param2=-3), "repeat count -3"),
        (item(12345), "unknown MAV_CMD 12345"),
    ],
)
def test_what_each_command_needs(bad: MissionItem, complaint: str) -> None:
    [problem] = mission_problems([bad])
    assert problem.startswith("item 1 (")
    assert complaint in problem


def test_speed_sentinels_of_the_mavlink_spec_are_allowed() -> None:
    # -1: keep the speed (change only the throttle); -2: back to the default
    assert mission_problems([item(CHANGE_SPEED, param1=1, param2=-1)]) == []
    assert mission_problems([item(CHANGE_SPEED, param1=1, param2=-2)]) == []


def test_zero_position_means_here_on_ardupilot_but_not_on_px4() -> None:
    loiter_here = [item(LOITER_TIME, param1=5), item(LAND)]
    assert mission_problems(loiter_here, "multirotor", "ardupilot") == []
    assert len(mission_problems(loiter_here, "multirotor", "px4")) == 2


def test_a_rover_cannot_take_off_or_land() -> None:
    problems = mission_problems(
        [item(TAKEOFF, alt=10), item(WAYPOINT, **HERE), item(LAND)], "rover", "ardupilot"
    )
    assert problems == [
        "item 1 (NAV_TAKEOFF): a rover cannot do this",
        "item 3 (NAV_LAND): a rover cannot do this",
    ]


def test_an_unset_parameter_is_taken_where_the_spec_gives_nan_a_meaning() -> None:
    """null is MAVLink's NaN: a yaw of NaN keeps the heading mode (common.xml), and an
    empty parameter is not read; a hold time, a loiter time or a speed has no "unset"."""
    keep_heading = [
        item(TAKEOFF, alt=10, param4=None),  # type: ignore[arg-type]
        item(WAYPOINT, param4=None, **HERE),  # type: ignore[arg-type]
        item(LOITER_TIME, param1=5, param4=None, **HERE),  # type: ignore[arg-type]
        item(LAND, param3=None, param4=None),  # type: ignore[arg-type]
        item(RTL, param1=None, param2=None, param3=None, param4=None),  # type: ignore[arg-type]
    ]
    assert mission_problems(keep_heading) == []
    problems = mission_problems(
        [
            item(WAYPOINT, param1=None, **HERE),  # type: ignore[arg-type]
            item(CHANGE_SPEED, param1=1, param2=None),  # type: ignore[arg-type]
        ]
    )
    assert problems == [
        "item 1 (NAV_WAYPOINT): param1 (Hold time) is empty (null), and this command gives "
        "it no unset value: give a number",
        "item 2 (DO_CHANGE_SPEED): param2 (Speed) is empty (null), and this command gives "
        "it no unset value: give a number",
    ]
