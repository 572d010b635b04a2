"""A lane plan as MAVLink mission items, the way QGC's Survey writes them
(TransectStyleComplexItem::_buildAndAppendMissionItems): per lane a waypoint at the
turnaround, one at the lane's entry followed by DO_SET_CAM_TRIGG_DIST (distance, no shutter
time, trigger once at once), one at the lane's exit followed by DO_SET_CAM_TRIGG_DIST 0
(stop, and trigger once: QGC's "trigger at entry and exit for full coverage"), and one at
the far turnaround. ArduPilot runs the "do" commands after a waypoint once it is reached
(AP_Mission::advance_current_nav_cmd), so the camera runs from entry to exit.

For "hover and capture", or a camera that cannot trigger on distance, the lane gets a
waypoint at each photo (held for a moment when hovering) followed by DO_DIGICAM_CONTROL
"shoot once", which every ArduPilot since 3.x runs in a mission. The mission starts with a
take-off and DO_CHANGE_SPEED to the survey's speed, and ends with RTL. Altitudes are
relative to home (MAV_FRAME_GLOBAL_RELATIVE_ALT). Every waypoint's yaw (param4) is unset
(NaN on the wire), as QGC writes a survey's: PX4 then faces along the lane (a yaw of 0 held
it facing north on east-west lanes, turning the camera's footprint 90° from the plan);
ArduPilot's copters take the yaw from WP_YAW_BEHAVIOR either way.

The take-off carries where the vehicle takes off, as QGC writes it for PX4 (its launch
position): PX4 climbs, then flies to a take-off item's position, so a take-off at 0, 0
sends it towards 0°N 0°E. ArduPilot's copters ignore the position and climb in place, so
the same item is right for both.
"""

from __future__ import annotations

from dataclasses import dataclass

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from backend.survey.planning.lanes import LanePlan
from common.geodesy import GeoPoint, LocalFrame
from protocol.messages import MissionItem

HOVER_HOLD_S = 1.0  # time to settle before each photo when hovering
# MISSION_ITEM_INT carries a "do" command's param5 in x unscaled; our MissionItem holds x as
# lat * 1e7, so param5 = 1 is a latitude of 1e-7.
_PARAM5_ONE = 1e-7


@dataclass(frozen=True, slots=True)
class SurveyMission:
    """The items, and for each lane the item numbers (1 is the first after home) of its
    entry and exit waypoints: a lane is flown once its exit is reached."""

    items: list[MissionItem]
    lanes: list[tuple[int, int]]


def _wp(
    frame: LocalFrame, point: tuple[float, float], alt: float, hold: float = 0.0
) -> MissionItem:
    lat, lon = frame.to_geo(point[0], point[1])
    return MissionItem(
        command=mavlink2.MAV_CMD_NAV_WAYPOINT,
        frame=mavlink2.MAV_FRAME_GLOBAL_RELATIVE_ALT,
        param1=hold,
        param4=None,  # yaw unset (NaN): the autopilot faces along the lane
        lat=lat,
        lon=lon,
        alt=alt,
    )


def _trigger_distance(distance_m: float) -> MissionItem:
    # param3 = 1 on both: a photo at the lane's entry and one at its exit, as QGC writes it.
    return MissionItem(
        command=mavlink2.MAV_CMD_DO_SET_CAM_TRIGG_DIST,
        frame=mavlink2.MAV_FRAME_MISSION,
        param1=distance_m,
        param2=0,
        param3=1,
    )


def _single_photo() -> MissionItem:
    # param1 session 0, param2 zoom 0, param3 zoom step 0, param4 focus 0, param5 shoot 1.
    return MissionItem(
        command=mavlink2.MAV_CMD_DO_DIGICAM_CONTROL,
        frame=mavlink2.MAV_FRAME_MISSION,
        lat=_PARAM5_ONE,
    )


def _change_speed(speed_ms: float) -> MissionItem:
    # param1 1 = ground speed, param2 the speed, param3 -1 = throttle unchanged.
    return MissionItem(
        command=mavlink2.MAV_CMD_DO_CHANGE_SPEED,
        frame=mavlink2.MAV_FRAME_MISSION,
        param1=1,
        param2=speed_ms,
        param3=-1,
    )


def survey_mission(
    plan: LanePlan,
    frame: LocalFrame,
    altitude_m: float,
    *,
    takeoff: GeoPoint | None,
    speed_ms: float | None = None,
    per_photo: bool = False,
    hover: bool = False,
    rtl: bool = True,
    start: tuple[float, float] | None = None,
    lead_in: bool = True,
) -> SurveyMission:
    """``takeoff``: where the vehicle takes off (its position on the ground), or None
    for no take-off (a mission for a vehicle in the air).
    ``start``: a first waypoint where the vehicle is (a mission resumed in the air).
    ``lead_in=False``: the first lane has no turnaround before it (it starts where the
    vehicle is, part way along a lane)."""
    items: list[MissionItem] = []
    lanes: list[tuple[int, int]] = []
    if takeoff is not None:
        items.append(
            MissionItem(
                command=mavlink2.MAV_CMD_NAV_TAKEOFF,
                frame=mavlink2.MAV_FRAME_GLOBAL_RELATIVE_ALT,
                param4=None,  # yaw unset: keep the heading
                lat=takeoff.lat,
                lon=takeoff.lon,
                alt=altitude_m,
            )
        )
    if start is not None:
        items.append(_wp(frame, start, altitude_m))
    if speed_ms is not None:
        # After the first nav command: it runs once that is done (take-off or resume point).
        items.append(_change_speed(speed_ms))
    for i, lane in enumerate(plan.lanes):
        turn_in, turn_out = plan.path[4 * i], plan.path[4 * i + 3]
        if lead_in or i > 0:
            items.append(_wp(frame, turn_in, altitude_m))
        entry = len(items) + 1
        if per_photo or hover:
            for photo in lane.photos:
                items.append(_wp(frame, photo, altitude_m, HOVER_HOLD_S if hover else 0.0))
                items.append(_single_photo())
            exit_ = len(items) - 1
        else:
            items.append(_wp(frame, lane.start, altitude_m))
            items.append(_trigger_distance(plan.trigger_distance_m))
            items.append(_wp(frame, lane.end, altitude_m))
            exit_ = len(items)
            items.append(_trigger_distance(0.0))
        lanes.append((entry, exit_))
        items.append(_wp(frame, turn_out, altitude_m))
    if rtl:
        items.append(
            MissionItem(
                command=mavlink2.MAV_CMD_NAV_RETURN_TO_LAUNCH, frame=mavlink2.MAV_FRAME_MISSION
            )
        )
    return SurveyMission(items, lanes)


def mission_items(
    plan: LanePlan,
    frame: LocalFrame,
    altitude_m: float,
    *,
    takeoff: GeoPoint | None,
    per_photo: bool = False,
    hover: bool = False,
    rtl: bool = True,
    speed_ms: float | None = None,
) -> list[MissionItem]:
    return survey_mission(
        plan,
        frame,
        altitude_m,
        takeoff=takeoff,
        speed_ms=speed_ms,
        per_photo=per_photo,
        hover=hover,
        rtl=rtl,
    ).items
