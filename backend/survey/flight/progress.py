"""A survey run from its plan, and its progress as the live feed tells it. Pure."""

from __future__ import annotations

import time
import uuid

from backend.survey.flight.run import (
    DroneRun,
    LaneRecord,
    SurveyRun,
    covered_fraction,
    geometry,
)
from backend.survey.planning.schemas import SurveyRequest
from backend.survey.planning.survey import SurveyPlan
from protocol.messages import SurveyDroneProgress, SurveyUpdate


def new_run(request: SurveyRequest, survey: SurveyPlan) -> SurveyRun:
    calc = survey.calc
    drones = []
    for part in survey.parts:
        lanes = [
            LaneRecord(start=(start[0], start[1]), end=(end[0], end[1]), entry=entry, exit=exit_)
            for (start, end), (entry, exit_) in zip(part.lane_paths, part.lane_items, strict=True)
        ]
        drones.append(DroneRun(vehicle_id=part.vehicle_id, items=part.items, lanes=lanes))
    return SurveyRun(
        id=uuid.uuid4().hex[:12],
        created=time.time(),
        request=request,
        altitude_m=calc.altitude_m,
        footprint_side_m=calc.footprint_side_m,
        footprint_frontal_m=calc.footprint_frontal_m,
        lane_spacing_m=calc.lane_spacing_m,
        trigger_distance_m=calc.trigger_distance_m,
        angle_deg=survey.angle_deg,
        drones=drones,
    )


def progress_of(run: SurveyRun) -> SurveyUpdate:
    """What the live feed's `survey` messages and the progress route say of a survey."""
    covered = covered_fraction(run, geometry(run))
    return SurveyUpdate(
        survey_id=run.id,
        state=run.state.value,
        lanes_done=run.lanes_done(),
        lanes_total=run.lanes_total(),
        photos=run.photo_count(),
        covered_pct=min(100.0, round(covered * 100, 3)),
        drones=[
            SurveyDroneProgress(
                vehicle_id=d.vehicle_id,
                state=d.state.value,
                lanes_done=d.lanes_done_before + sum(lane.done for lane in d.lanes),
                lanes_total=d.lanes_done_before + len(d.lanes),
                photos=len(d.photos),
                reason=d.reason,
            )
            for d in run.drones
        ],
        handover_lanes=run.offer.lanes_moved if run.offer else None,
    )
