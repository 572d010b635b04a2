"""Surveys without a hub: a planned run whose drones are all flying; QGroundControl's
survey plan (tests/data/qgc) planned for one drone, and two missions compared item by item;
a drone's exported `QGC WPL 110` mission read back by pymavlink's own reader."""

from __future__ import annotations

import tempfile
from pathlib import Path

import pytest
from pymavlink import mavwp

from backend.survey.files.items import params_to_item
from backend.survey.files.qgc_plan import read_qgc_survey
from backend.survey.flight.progress import new_run
from backend.survey.flight.run import DroneState, SurveyRun, SurveyState
from backend.survey.planning.schemas import SurveyRequest
from backend.survey.planning.survey import Fleet, plan_survey, summary
from common.geodesy import GeoPoint, LocalFrame
from protocol.messages import MissionItem

LAT, LON = 47.0, 8.0
QGC_DATA = Path(__file__).resolve().parents[1] / "data" / "qgc"
QGC_HOME = (47.3977, 8.5456, 488.0)
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


def read_wpl(text: str) -> tuple[tuple[float, float, float] | None, list[MissionItem]]:
    """(home, items after home) from a `QGC WPL 110` file, as MAVProxy loads one (mavwp): the
    hub only writes these files, so they are checked with a reader that is not ours. mavwp
    reads a file by name, numbers the lines in order, and line 0 is home."""
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "mission.waypoints"
        path.write_text(text)
        loader = mavwp.MAVWPLoader()
        loader.load(str(path))
    home = None
    items = []
    for point in loader.wpoints:
        params = [point.param1, point.param2, point.param3, point.param4, point.x, point.y, point.z]
        if point.seq == 0:
            home = (point.x, point.y, point.z)
            continue
        items.append(params_to_item(point.command, point.frame, params, bool(point.autocontinue)))
    return home, items


def survey_plan_items() -> list[MissionItem]:
    """The mission QGroundControl's survey plan (tests/data/qgc/survey.plan) gives one drone
    at QGC_HOME."""
    fields = read_qgc_survey((QGC_DATA / "survey.plan").read_text())
    request = SurveyRequest.model_validate({**fields, "vehicle_ids": ["d1"]})
    home = GeoPoint(QGC_HOME[0], QGC_HOME[1], QGC_HOME[2])
    survey = plan_survey(request, [Fleet("d1", home, home)])
    return survey.parts[0].items


def same_items(a: list[MissionItem], b: list[MissionItem]) -> None:
    """The two missions are the same, item by item (positions to 1e-7)."""
    assert len(a) == len(b)
    for x, y in zip(a, b, strict=True):
        assert (x.command, x.frame, x.autocontinue) == (y.command, y.frame, y.autocontinue)
        for field in ("param1", "param2", "param3", "param4", "lat", "lon", "alt"):
            assert getattr(x, field) == pytest.approx(getattr(y, field), abs=1e-7), field
