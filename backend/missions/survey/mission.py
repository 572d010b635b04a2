"""A lane plan as MAVLink mission items, the way QGC's Survey writes them
(TransectStyleComplexItem): per lane a waypoint at the turnaround, one at the lane's start
followed by DO_SET_CAM_TRIGG_DIST (distance, no shutter time, trigger once at once), one at
the lane's end followed by DO_SET_CAM_TRIGG_DIST 0 (stop), and one at the far turnaround.

For "hover and capture", or a camera that cannot trigger on distance, the lane gets a
waypoint at each photo (held for a moment when hovering) followed by IMAGE_START_CAPTURE
for one image, as QGC does. The mission starts with a take-off and ends with RTL.
Altitudes are relative to home (MAV_FRAME_GLOBAL_RELATIVE_ALT).
"""

from __future__ import annotations

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from backend.missions.survey.planner import LanePlan
from common.geodesy import LocalFrame
from protocol.messages import MissionItem

HOVER_HOLD_S = 1.0  # time to settle before each photo when hovering


def _wp(
    frame: LocalFrame, point: tuple[float, float], alt: float, hold: float = 0.0
) -> MissionItem:
    lat, lon = frame.to_geo(point[0], point[1])
    return MissionItem(
        command=mavlink2.MAV_CMD_NAV_WAYPOINT,
        frame=mavlink2.MAV_FRAME_GLOBAL_RELATIVE_ALT,
        param1=hold,
        lat=lat,
        lon=lon,
        alt=alt,
    )


def _trigger_distance(distance_m: float) -> MissionItem:
    return MissionItem(
        command=mavlink2.MAV_CMD_DO_SET_CAM_TRIGG_DIST,
        frame=mavlink2.MAV_FRAME_MISSION,
        param1=distance_m,
        param2=0,
        param3=1 if distance_m > 0 else 0,
    )


def _single_photo() -> MissionItem:
    # param1 camera id (0 all), param2 interval 0, param3 one image, param4 sequence 0.
    return MissionItem(
        command=mavlink2.MAV_CMD_IMAGE_START_CAPTURE,
        frame=mavlink2.MAV_FRAME_MISSION,
        param1=0,
        param2=0,
        param3=1,
    )


def mission_items(
    plan: LanePlan,
    frame: LocalFrame,
    altitude_m: float,
    *,
    per_photo: bool = False,
    hover: bool = False,
    takeoff: bool = True,
    rtl: bool = True,
) -> list[MissionItem]:
    items: list[MissionItem] = []
    if takeoff:
        items.append(
            MissionItem(
                command=mavlink2.MAV_CMD_NAV_TAKEOFF,
                frame=mavlink2.MAV_FRAME_GLOBAL_RELATIVE_ALT,
                alt=altitude_m,
            )
        )
    for i, lane in enumerate(plan.lanes):
        turn_in, turn_out = plan.path[4 * i], plan.path[4 * i + 3]
        items.append(_wp(frame, turn_in, altitude_m))
        if per_photo or hover:
            for photo in lane.photos:
                items.append(_wp(frame, photo, altitude_m, HOVER_HOLD_S if hover else 0.0))
                items.append(_single_photo())
        else:
            items.append(_wp(frame, lane.start, altitude_m))
            items.append(_trigger_distance(plan.trigger_distance_m))
            items.append(_wp(frame, lane.end, altitude_m))
            items.append(_trigger_distance(0.0))
        items.append(_wp(frame, turn_out, altitude_m))
    if rtl:
        items.append(
            MissionItem(
                command=mavlink2.MAV_CMD_NAV_RETURN_TO_LAUNCH, frame=mavlink2.MAV_FRAME_MISSION
            )
        )
    return items
