"""Area survey: a plan preview with no side effects (issue 17).

The preview plans the lanes from the camera, splits the area across the chosen drones and
returns one mission per drone, each with the same mission check an upload runs.
"""

from __future__ import annotations

import asyncio

from backend.api.deps import HubDep
from backend.api.security import SecuredRouter, requires
from backend.auth.policy import Permission
from backend.errors import InvalidRequest
from backend.fleet.safety_gate import snapshot_of
from backend.missions.schemas import Mission, MissionCheckResponse
from backend.missions.survey.camera import CameraError
from backend.missions.survey.planner import PlanError
from backend.missions.survey.schemas import SurveyPart, SurveyPreview, SurveyRequest
from backend.missions.survey.service import Fleet, percent, plan_survey
from backend.safety.snapshot import home, position

router = SecuredRouter(tags=["surveys"])


@router.post(
    "/surveys/preview", response_model=SurveyPreview, openapi_extra=requires(Permission.COMMAND)
)
async def preview_survey(body: SurveyRequest, hub: HubDep) -> SurveyPreview:
    """Plan a survey and split it across the chosen drones, without uploading anything:
    the camera's numbers, the coverage of the photos' footprints, and per drone its
    mission, its times and the safety rails' check of that mission."""
    if len(set(body.vehicle_ids)) != len(body.vehicle_ids):
        raise InvalidRequest("vehicle_ids", "each vehicle may be chosen once")
    records = {vid: hub.registry.get(vid) for vid in body.vehicle_ids}
    fleet = []
    for vid, record in records.items():
        snapshot = snapshot_of(record)
        here, base = position(snapshot), home(snapshot)
        if here is None or base is None:
            raise InvalidRequest(
                "vehicle_ids", f"vehicle {vid} has no position or home yet; wait for its GPS"
            )
        fleet.append(Fleet(vid, here, base))
    try:
        survey = await asyncio.to_thread(plan_survey, body, fleet)
    except CameraError as exc:
        raise InvalidRequest("camera", str(exc)) from exc
    except PlanError as exc:
        raise InvalidRequest("area", str(exc)) from exc
    parts = []
    for planned in survey.parts:
        p = planned.part
        record = records[p.drone.name]
        check = await asyncio.to_thread(hub.safety.check_mission, record, planned.items)
        parts.append(
            SurveyPart(
                vehicle_id=p.drone.name,
                mission=Mission(items=planned.items),
                lanes=len(p.plan.lanes),
                photo_count=p.plan.photo_count,
                path_length_m=p.plan.path_length_m,
                transit_s=p.transit_s,
                survey_s=p.survey_s,
                home_s=p.home_s,
                total_s=p.total_s,
                lane_paths=planned.lane_paths,
                check=MissionCheckResponse.from_plan_check(check),
            )
        )
    calc = survey.calc
    return SurveyPreview(
        ok=all(part.check.ok for part in parts),
        altitude_m=calc.altitude_m,
        gsd_cm=calc.gsd_cm,
        footprint_side_m=calc.footprint_side_m,
        footprint_frontal_m=calc.footprint_frontal_m,
        lane_spacing_m=calc.lane_spacing_m,
        trigger_distance_m=calc.trigger_distance_m,
        angle_deg=survey.angle_deg,
        area_m2=survey.area_m2,
        coverage_pct=percent(survey.coverage),
        coverage_at_overlaps_pct=percent(survey.coverage_at_overlaps),
        photo_count=sum(part.photo_count for part in parts),
        lanes=sum(part.lanes for part in parts),
        parts=parts,
    )
