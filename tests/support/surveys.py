"""Surveys in flight without a hub: a planned run whose drones are all flying."""

from __future__ import annotations

from backend.survey.flight.run import DroneState, SurveyRun, SurveyState
from backend.survey.planning.schemas import SurveyRequest
from backend.survey.planning.survey import Fleet, plan_survey, summary
from backend.survey.service import new_run
from common.geodesy import GeoPoint, LocalFrame

LAT, LON = 47.0, 8.0
FRAME = LocalFrame(LAT, LON)


def ring(width: float, depth: float) -> list[list[float]]:
    corners = [(0, 0), (width, 0), (width, depth), (0, depth), (0, 0)]
    return [list(reversed(FRAME.to_geo(x, y))) for x, y in corners]


def flying_run(vehicles: int = 3) -> SurveyRun:
    request = SurveyRequest.model_validate(
        {
            "area": {"type": "Polygon", "coordinates": [ring(300, 200)]},
            "camera": "sony_a6000_16mm",
            "altitude_m": 40,
            "angle_deg": 0,
            "vehicle_ids": [f"d{i}" for i in range(vehicles)],
        }
    )
    fleet = []
    for i in range(vehicles):
        lat, lon = FRAME.to_geo(-20.0 + 5 * i, -30.0)
        fleet.append(Fleet(f"d{i}", GeoPoint(lat, lon, 500), GeoPoint(lat, lon, 500)))
    run = new_run(request, summary(plan_survey(request, fleet)))
    run.state = SurveyState.FLYING
    run.started = 1_000.0
    for drone in run.drones:
        drone.state = DroneState.FLYING
    return run
