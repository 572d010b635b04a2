"""Area surveys (issue 17): a plan preview with no side effects; create (plan, split and
check every part); start (upload every mission, then start them together); progress; the
hand-over offer and its acceptance; taking one drone out; abort.

The preview plans the lanes from the camera, splits the area across the chosen drones and
returns one mission per drone, each with the same mission check an upload runs.
"""

from __future__ import annotations

import asyncio
from functools import partial
from typing import Annotated, Any, Literal

from fastapi import Path, Query, Request
from fastapi.responses import JSONResponse, PlainTextResponse, Response
from pydantic import BaseModel, Field
from starlette.convertors import Convertor, register_url_convertor

from backend.api.deps import HubDep
from backend.api.responses import ErrorMessage
from backend.api.security import CurrentPrincipal, SecuredRouter, requires
from backend.auth.policy import Permission
from backend.errors import Conflict, InvalidRequest, RequestTooLarge
from backend.fleet.safety_gate import snapshot_of
from backend.missions.schemas import Mission, MissionCheckResponse
from backend.safety.snapshot import home, position
from backend.survey.files.areas import mission_path_geojson
from backend.survey.files.items import MAX_FILE_BYTES
from backend.survey.files.qgc_plan import to_qgc_plan
from backend.survey.files.wpl import to_wpl
from backend.survey.flight.run import HandoverOffer, SurveyRun
from backend.survey.planning.camera import PRESETS
from backend.survey.planning.schemas import SurveyPart, SurveyPreview, SurveyRequest
from backend.survey.planning.survey import Fleet, percent
from protocol.messages import SurveyUpdate, VehicleId

router = SecuredRouter(tags=["surveys"])


class CameraPreset(BaseModel):
    """A camera a survey may name by ``id`` (its ``camera.preset``), with its figures."""

    id: str
    name: str
    sensor_width_mm: float
    sensor_height_mm: float
    image_width_px: int
    image_height_px: int
    focal_length_mm: float
    distance_trigger: bool = Field(description="False: one DO_DIGICAM_CONTROL per photo")


@router.get(
    "/surveys/cameras", response_model=list[CameraPreset], openapi_extra=requires(Permission.READ)
)
async def camera_presets() -> list[CameraPreset]:
    """The camera presets, so a client offers exactly the hub's (the dashboard does)."""
    return [
        CameraPreset(
            id=key,
            name=camera.name,
            sensor_width_mm=camera.sensor_width_mm,
            sensor_height_mm=camera.sensor_height_mm,
            image_width_px=camera.image_width_px,
            image_height_px=camera.image_height_px,
            focal_length_mm=camera.focal_length_mm,
            distance_trigger=camera.distance_trigger,
        )
        for key, camera in PRESETS.items()
    ]


@router.post(
    "/surveys/preview", response_model=SurveyPreview, openapi_extra=requires(Permission.COMMAND)
)
async def preview_survey(body: SurveyRequest, request: Request, hub: HubDep) -> SurveyPreview:
    """Plan a survey and split it across the chosen drones, without uploading anything:
    the camera's numbers, the coverage of the photos' footprints, and per drone its
    mission, its times and the safety rails' check of that mission. A plan over the hub's
    limits (lanes, photos, a drone's mission items, planning time) is refused with a 422
    naming the estimate and the limit's setting (docs/security.md)."""
    if len(set(body.vehicle_ids)) != len(body.vehicle_ids):
        raise InvalidRequest("vehicle_ids", "each vehicle may be chosen once")
    known = {record.id for record in hub.registry.all()}
    if unknown := [vid for vid in body.vehicle_ids if vid not in known]:
        # A body naming a vehicle the hub has never seen is a bad body (422), not a missing
        # resource: the route itself exists.
        raise InvalidRequest("vehicle_ids", f"unknown vehicles: {', '.join(unknown[:10])}")
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
    survey = await hub.surveys.planner.plan(body, fleet, partial(client_gone, request))
    parts = []
    for part in survey.parts:
        record = records[part.vehicle_id]
        check = await asyncio.to_thread(hub.safety.check_mission, record, part.items)
        parts.append(
            SurveyPart(
                vehicle_id=part.vehicle_id,
                mission=Mission(items=part.items),
                lanes=len(part.lane_paths),
                photo_count=part.photo_count,
                path_length_m=part.path_length_m,
                transit_s=part.transit_s,
                survey_s=part.survey_s,
                home_s=part.home_s,
                total_s=part.total_s,
                lane_paths=part.lane_paths,
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


class _SurveyIdConvertor(Convertor[str]):
    """A survey id in a path is hex, so /surveys/preview and /surveys/import are never
    taken for one: a GET on them is a 405 naming POST, not the survey route's 422."""

    regex = "[0-9a-f]{1,32}"

    def convert(self, value: str) -> str:
        return value

    def to_string(self, value: str) -> str:
        return value


# Starlette's convertors are a registry keyed by name; this one is ours alone.
register_url_convertor("survey_id", _SurveyIdConvertor())

SurveyIdPath = Annotated[str, Path(min_length=1, max_length=32, pattern=r"^[0-9a-f]+$")]


class SurveyDetail(BaseModel):
    progress: SurveyUpdate
    survey: SurveyRun = Field(
        description="The plan, each drone's mission and lanes (flown or not), its photos "
        "([lat, lon] from CAMERA_FEEDBACK) and any hand-over on offer"
    )


class SurveyList(BaseModel):
    surveys: list[SurveyUpdate]


def _detail(hub: HubDep, run: SurveyRun) -> SurveyDetail:
    return SurveyDetail(progress=hub.surveys.update_of(run), survey=run)


@router.post(
    "/surveys",
    response_model=SurveyDetail,
    status_code=201,
    openapi_extra=requires(Permission.COMMAND),
)
async def create_survey(
    body: SurveyRequest, request: Request, principal: CurrentPrincipal, hub: HubDep
) -> SurveyDetail:
    """Plan and split a survey and check every drone's mission against the safety rails;
    nothing is uploaded until it is started. Each chosen drone must be connected, ready,
    on the ground and in no other survey (422 naming it otherwise); a part that breaks a
    rail refuses the whole survey (422, each violation naming its vehicle); a plan over
    the hub's limits is refused as the preview's is."""
    return _detail(hub, await hub.surveys.create(body, principal, partial(client_gone, request)))


async def client_gone(request: Request) -> None:
    """Finishes when the client closes the connection (the body has been read, so the
    next message from the server is the disconnect)."""
    while (await request.receive())["type"] != "http.disconnect":
        pass


@router.get("/surveys", response_model=SurveyList, openapi_extra=requires(Permission.READ))
async def list_surveys(hub: HubDep) -> SurveyList:
    """The surveys this hub is following (planned, flying, or awaiting a hand-over)."""
    return SurveyList(surveys=[hub.surveys.update_of(run) for run in hub.surveys.active()])


@router.get(
    "/surveys/{survey_id:survey_id}",
    response_model=SurveyDetail,
    openapi_extra=requires(Permission.READ),
)
async def get_survey(survey_id: SurveyIdPath, hub: HubDep) -> SurveyDetail:
    return _detail(hub, await hub.surveys.find(survey_id))


@router.get(
    "/surveys/{survey_id}/progress",
    response_model=SurveyUpdate,
    openapi_extra=requires(Permission.READ),
)
async def survey_progress(survey_id: SurveyIdPath, hub: HubDep) -> SurveyUpdate:
    """Lanes flown, photos taken and the area their footprints cover, overall and per
    drone; the live feed carries the same as `survey` messages."""
    return hub.surveys.update_of(await hub.surveys.find(survey_id))


@router.post(
    "/surveys/{survey_id}/start",
    response_model=SurveyDetail,
    openapi_extra=requires(Permission.COMMAND),
)
async def start_survey(
    survey_id: SurveyIdPath, principal: CurrentPrincipal, hub: HubDep
) -> SurveyDetail:
    """Upload every drone's mission (each checked again on the way), then start them
    together as QGroundControl starts a mission: ArduPilot a guided take-off, then AUTO;
    PX4 its mission mode (MISSION), then arm. An upload refused anywhere starts nothing
    (409); a drone that fails to start (named in its reason) drops out, is disarmed if
    it is still on the ground, and its lanes are offered."""
    return _detail(hub, await hub.surveys.start(survey_id, principal))


@router.get(
    "/surveys/{survey_id}/handover",
    response_model=HandoverOffer | None,
    openapi_extra=requires(Permission.READ),
)
async def handover_offer(survey_id: SurveyIdPath, hub: HubDep) -> HandoverOffer | None:
    """The hand-over on offer, if any: which drone dropped out and why, and per drone still
    flying its new mission (from where it is) and the time it needs to finish."""
    return (await hub.surveys.find(survey_id)).offer


@router.post(
    "/surveys/{survey_id}/handover/accept",
    response_model=SurveyDetail,
    openapi_extra=requires(Permission.COMMAND),
)
async def accept_handover(
    survey_id: SurveyIdPath, principal: CurrentPrincipal, hub: HubDep
) -> SurveyDetail:
    """Upload the offered missions; each drone flies on from where it is."""
    return _detail(hub, await hub.surveys.accept(survey_id, principal))


@router.post(
    "/surveys/{survey_id}/vehicles/{vehicle_id}/abort",
    response_model=SurveyDetail,
    openapi_extra=requires(Permission.COMMAND),
)
async def abort_vehicle(
    survey_id: SurveyIdPath,
    vehicle_id: Annotated[VehicleId, Path()],
    principal: CurrentPrincipal,
    hub: HubDep,
) -> SurveyDetail:
    """Take one drone out of the survey: it returns to launch, and its unflown lanes are
    offered to the others."""
    return _detail(hub, await hub.surveys.drop_vehicle(survey_id, vehicle_id, principal))


@router.post(
    "/surveys/{survey_id}/abort",
    response_model=SurveyDetail,
    openapi_extra=requires(Permission.COMMAND),
)
async def abort_survey(
    survey_id: SurveyIdPath, principal: CurrentPrincipal, hub: HubDep
) -> SurveyDetail:
    """End the survey: every drone still flying it returns to launch."""
    return _detail(hub, await hub.surveys.abort(survey_id, principal))


class SurveyFile(BaseModel):
    format: Literal["plan", "kml", "geojson"] = Field(
        description="plan: a QGroundControl .plan with a Survey item (its polygon, camera, "
        "altitude or GSD, overlaps, angle, turnaround); kml: the first Polygon of a KML file "
        "(Google Earth); geojson: a Polygon, Feature or FeatureCollection"
    )
    content: str = Field(max_length=MAX_FILE_BYTES, description="the file's text")


@router.post(
    "/surveys/import",
    response_model=dict[str, Any],
    openapi_extra=requires(Permission.COMMAND),
)
async def import_survey_area(
    body: SurveyFile, principal: CurrentPrincipal, hub: HubDep
) -> Response:
    """A survey request's fields from another tool's file (no side effects): at least the
    `area`, and from a QGC Survey also its camera and settings. Add `vehicle_ids` (and
    anything to change) and send it to `POST /surveys` or the preview. It needs the
    planning permission (as the preview does), and is bounded: the file's size (413) and
    its polygon's vertices (422), and `survey_imports_per_minute` per user (429)."""
    settings = hub.settings
    limiter = hub.surveys.import_limiter
    limiter.check(principal.name, "survey imports")
    limiter.hit(principal.name)  # every attempt counts: a bad file is parsed too
    size = len(body.content.encode())
    if size > settings.survey_import_max_bytes:
        raise RequestTooLarge(
            f"the file is {size:,} bytes; the limit is {settings.survey_import_max_bytes:,} "
            "(survey_import_max_bytes)"
        )
    # Parsed in a worker process (backend/survey/plan_workers.py), never on the event loop.
    content = await hub.surveys.planner.read_area_file(body.format, body.content)
    return Response(content, media_type="application/json")


@router.get(
    "/surveys/{survey_id}/vehicles/{vehicle_id}/mission",
    openapi_extra=requires(Permission.READ),
    responses={
        200: {"content": {"application/json": {}, "text/plain": {}}},
        409: {
            "description": "A `.plan` or `.waypoints` file for a vehicle that has not "
            "reported its home yet (both files carry it)",
            "model": ErrorMessage,
        },
    },
)
async def export_survey_mission(
    survey_id: SurveyIdPath,
    vehicle_id: Annotated[VehicleId, Path()],
    hub: HubDep,
    format: Annotated[Literal["plan", "wpl", "geojson"], Query()] = "plan",
) -> Response:
    """One drone's survey mission as a file other tools open: a QGroundControl `.plan`,
    a `QGC WPL 110` waypoint file (Mission Planner, MAVProxy), or its path as GeoJSON."""
    run = await hub.surveys.find(survey_id)
    drone = run.drone(vehicle_id)
    if drone is None:
        raise InvalidRequest("vehicle_id", f"vehicle {vehicle_id} is not in survey {survey_id}")
    name = f"survey-{survey_id}-{vehicle_id}"
    if format == "geojson":
        return JSONResponse(
            mission_path_geojson(drone.items),
            headers={"Content-Disposition": f'attachment; filename="{name}.geojson"'},
        )
    record = {r.id: r for r in hub.registry.all()}.get(vehicle_id)
    state = record.state if record is not None else None
    if (
        state is None
        or state.home_lat is None
        or state.home_lon is None
        or state.home_alt_msl is None
    ):
        # Never 0, 0, 0: a tool that takes the file's home would put it at 0°N 0°E.
        raise Conflict(
            f"{vehicle_id} has not reported its home yet, which a .plan or .waypoints file "
            "carries; the GeoJSON path does not need it"
        )
    home = (state.home_lat, state.home_lon, state.home_alt_msl)
    if format == "wpl":
        return PlainTextResponse(
            to_wpl(drone.items, home),
            headers={"Content-Disposition": f'attachment; filename="{name}.waypoints"'},
        )
    return JSONResponse(
        to_qgc_plan(drone.items, home),
        headers={"Content-Disposition": f'attachment; filename="{name}.plan"'},
    )
