"""A survey from a request: the camera, the lanes, the fleet split, one mission per drone,
and the coverage check. Pure: the caller supplies where each drone is and its home, and
checks each mission against the safety rails."""

from __future__ import annotations

import math
from dataclasses import dataclass

import shapely

from backend.survey.planning.camera import Camera, CameraCalc, calculate, camera_of, manual, preset
from backend.survey.planning.coverage import covered_fraction, swaths
from backend.survey.planning.geo import polygon_from_geojson
from backend.survey.planning.limits import SurveyLimits, check_estimate, check_missions, estimate
from backend.survey.planning.mission import survey_mission
from backend.survey.planning.planner import PlanError
from backend.survey.planning.report import best_angle
from backend.survey.planning.schemas import ManualCamera, SurveyRequest
from backend.survey.planning.split import Drone, Part, split
from common.geodesy import GeoPoint, LocalFrame
from protocol.messages import MissionItem

MAX_TRANSIT_M = 20_000.0  # a drone further than this from the area is not offered a part


@dataclass(frozen=True, slots=True)
class Fleet:
    vehicle_id: str
    position: GeoPoint
    home: GeoPoint


@dataclass(frozen=True, slots=True)
class PlannedPart:
    part: Part
    items: list[MissionItem]
    lane_paths: list[list[list[float]]]
    # Per lane, the item numbers of its entry and exit waypoints (progress, hand-over).
    lane_items: list[tuple[int, int]]


@dataclass(frozen=True, slots=True)
class Survey:
    calc: CameraCalc
    frame: LocalFrame
    angle_deg: float
    area_m2: float
    coverage: float
    coverage_at_overlaps: float
    parts: list[PlannedPart]


@dataclass(frozen=True, slots=True)
class PartPlan:
    """What the hub keeps of a drone's part: its mission, its lanes' ends and its figures,
    without the planner's geometry (every photo's point). Small, so it crosses from a
    planning worker process quickly (backend/survey/plan_workers.py)."""

    vehicle_id: str
    items: list[MissionItem]
    lane_paths: list[list[list[float]]]  # per lane, [[lat, lon] of its start, of its end]
    lane_items: list[tuple[int, int]]  # per lane, the item numbers of its entry and exit
    photo_count: int
    path_length_m: float
    transit_s: float
    survey_s: float
    home_s: float

    @property
    def total_s(self) -> float:
        return self.transit_s + self.survey_s + self.home_s


@dataclass(frozen=True, slots=True)
class SurveyPlan:
    """A planned survey as the preview answers it and a survey run starts from."""

    calc: CameraCalc
    angle_deg: float
    area_m2: float
    coverage: float
    coverage_at_overlaps: float
    parts: list[PartPlan]


def summary(survey: Survey) -> SurveyPlan:
    parts = [
        PartPlan(
            vehicle_id=planned.part.drone.name,
            items=planned.items,
            lane_paths=planned.lane_paths,
            lane_items=planned.lane_items,
            photo_count=planned.part.plan.photo_count,
            path_length_m=planned.part.plan.path_length_m,
            transit_s=planned.part.transit_s,
            survey_s=planned.part.survey_s,
            home_s=planned.part.home_s,
        )
        for planned in survey.parts
    ]
    return SurveyPlan(
        calc=survey.calc,
        angle_deg=survey.angle_deg,
        area_m2=survey.area_m2,
        coverage=survey.coverage,
        coverage_at_overlaps=survey.coverage_at_overlaps,
        parts=parts,
    )


def _camera(request: SurveyRequest) -> Camera:
    if isinstance(request.camera, str):
        return preset(request.camera)
    assert not isinstance(request.camera, ManualCamera)
    return camera_of(name="custom", **request.camera.model_dump())


def camera_calc(request: SurveyRequest) -> CameraCalc:
    """The request's camera at its height and overlaps; a manual camera's spacing and
    trigger distance as given (its overlaps are not used)."""
    camera = request.camera
    if isinstance(camera, ManualCamera):
        if request.altitude_m is None:  # the request's validator says so first
            raise ValueError("a manual camera needs altitude_m")
        return manual(
            altitude_m=request.altitude_m,
            lane_spacing_m=camera.lane_spacing_m,
            trigger_distance_m=camera.trigger_distance_m,
            distance_trigger=camera.distance_trigger,
        )
    return calculate(
        _camera(request),
        altitude_m=request.altitude_m,
        gsd_cm=request.gsd_cm,
        side_overlap_pct=request.side_overlap_pct,
        front_overlap_pct=request.front_overlap_pct,
    )


def plan_survey(
    request: SurveyRequest, fleet: list[Fleet], limits: SurveyLimits | None = None
) -> Survey:
    """With `limits`, the plan is estimated first and refused (PlanTooLarge) past them,
    and so is a drone's planned mission longer than its store."""
    calc = camera_calc(request)
    area, frame = polygon_from_geojson(request.area.model_dump())
    per_photo = not calc.distance_trigger or request.hover_and_capture
    if limits is not None:
        found = estimate(
            area, calc, drones=len(fleet), angle_deg=request.angle_deg, per_photo=per_photo
        )
        check_estimate(found, limits)
    drones = []
    for vehicle in fleet:
        where = frame.to_local(vehicle.position.lat, vehicle.position.lon)
        home = frame.to_local(vehicle.home.lat, vehicle.home.lon)
        distance = shapely.Point(where).distance(area)
        if distance > MAX_TRANSIT_M:
            raise PlanError(
                f"vehicle {vehicle.vehicle_id} is {distance / 1000:.1f} km from the area; "
                f"choose drones within {MAX_TRANSIT_M / 1000:.0f} km"
            )
        drones.append(Drone(vehicle.vehicle_id, where, home, request.speed_ms))
    angle = request.angle_deg
    if angle is None:
        angle = best_angle(area, calc, request.speed_ms, turnaround_m=request.turnaround_m)
    parts = split(area, calc, drones, angle_deg=angle, turnaround_m=request.turnaround_m)
    # The photos' footprints united lane by lane (the same union, a few shapes per lane).
    shots = [
        f for p in parts for f in swaths(p.plan, calc.footprint_side_m, calc.footprint_frontal_m)
    ]
    tight = [
        f
        for p in parts
        for f in swaths(p.plan, calc.lane_spacing_m * 1.0001, calc.trigger_distance_m * 1.0001)
    ]
    positions = {vehicle.vehicle_id: vehicle.position for vehicle in fleet}
    planned = []
    for p in parts:
        mission = survey_mission(
            p.plan,
            frame,
            calc.altitude_m,
            # The drone takes off where it stands.
            takeoff=positions[p.drone.name],
            speed_ms=request.speed_ms,
            per_photo=not calc.distance_trigger,
            hover=request.hover_and_capture,
        )
        planned.append(
            PlannedPart(
                part=p,
                items=mission.items,
                lane_paths=[_latlon(frame, [lane.start, lane.end]) for lane in p.plan.lanes],
                lane_items=mission.lanes,
            )
        )
    if limits is not None:
        check_missions({p.part.drone.name: len(p.items) for p in planned}, limits)
    return Survey(
        calc=calc,
        frame=frame,
        angle_deg=angle,
        area_m2=float(area.area),
        coverage=covered_fraction(area, shots),
        coverage_at_overlaps=covered_fraction(area, tight),
        parts=planned,
    )


def _latlon(frame: LocalFrame, points: list[tuple[float, float]]) -> list[list[float]]:
    return [list(frame.to_geo(x, y)) for x, y in points]


def percent(fraction: float) -> float:
    return math.floor(fraction * 1e6) / 1e4
