"""Area surveys (issue 17): a plan preview with no side effects; create (plan, split and
check every part); start (upload every mission, then start them together); progress; the
hand-over offer and its acceptance; taking one drone out; abort.

The preview plans the lanes from the camera, splits the area across the chosen drones and
returns one mission per drone, each with the same mission check an upload runs.
"""

from __future__ import annotations

from functools import partial
from typing import Annotated, Any, Literal

from fastapi import Path, Query, Request
from fastapi.responses import JSONResponse, PlainTextResponse, Response
from pydantic import BaseModel, Field
from starlette.convertors import Convertor, register_url_convertor

from backend.api.deps import RegistryDep
from backend.api.responses import ErrorMessage
from backend.api.security import CurrentPrincipal, SecuredRouter, requires
from backend.auth.policy import Permission
from backend.survey.deps import SurveysDep
from backend.survey.files.items import MAX_FILE_BYTES
from backend.survey.fleet_cameras import fleet_cameras
from backend.survey.flight.run import HandoverOffer, SurveyRun
from backend.survey.planning.camera import PRESETS
from backend.survey.planning.schemas import SurveyPreview, SurveyRequest
from backend.survey.service import MissionFormat
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
    vehicle_ids: list[VehicleId] = Field(
        default_factory=list,
        description="The vehicles whose agents carry this camera (a `fleet:` preset); "
        "empty for a catalogue camera",
    )


@router.get(
    "/surveys/cameras", response_model=list[CameraPreset], openapi_extra=requires(Permission.READ)
)
async def camera_presets(registry: RegistryDep) -> list[CameraPreset]:
    """The camera presets, so a client offers exactly the hub's (the dashboard does): first
    each camera the fleet's agents said they carry (`fleet:` and its figures, named after
    its vehicles), then the catalogue's."""
    fleet = [
        CameraPreset(
            id=carried.preset_id,
            **carried.camera.model_dump(exclude={"landscape", "name"}),
            name=carried.name,
            vehicle_ids=list(carried.vehicle_ids),
        )
        for carried in fleet_cameras(registry.all())
    ]
    return fleet + [
        CameraPreset(id=key, **camera.model_dump(exclude={"landscape"}))
        for key, camera in PRESETS.items()
    ]


@router.post(
    "/surveys/preview", response_model=SurveyPreview, openapi_extra=requires(Permission.COMMAND)
)
async def preview_survey(
    body: SurveyRequest, request: Request, surveys: SurveysDep
) -> SurveyPreview:
    """Plan a survey and split it across the chosen drones, without uploading anything:
    the camera's numbers, the coverage of the photos' footprints, and per drone its
    mission, its times and the safety rails' check of that mission. A plan over the hub's
    limits (lanes, photos, a drone's mission items, planning time) is refused with a 422
    naming the estimate and the limit's setting (docs/security.md)."""
    return await surveys.preview(body, partial(client_gone, request))


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


def _detail(surveys: SurveysDep, run: SurveyRun) -> SurveyDetail:
    return SurveyDetail(progress=surveys.update_of(run), survey=run)


@router.post(
    "/surveys",
    response_model=SurveyDetail,
    status_code=201,
    openapi_extra=requires(Permission.COMMAND),
)
async def create_survey(
    body: SurveyRequest, request: Request, principal: CurrentPrincipal, surveys: SurveysDep
) -> SurveyDetail:
    """Plan and split a survey and check every drone's mission against the safety rails;
    nothing is uploaded until it is started. Each chosen drone must be connected, ready,
    on the ground and in no other survey (422 naming it otherwise); a part that breaks a
    rail refuses the whole survey (422, each violation naming its vehicle); a plan over
    the hub's limits is refused as the preview's is."""
    return _detail(surveys, await surveys.create(body, principal, partial(client_gone, request)))


async def client_gone(request: Request) -> None:
    """Finishes when the client closes the connection (the body has been read, so the
    next message from the server is the disconnect)."""
    while (await request.receive())["type"] != "http.disconnect":
        pass


@router.get("/surveys", response_model=SurveyList, openapi_extra=requires(Permission.READ))
async def list_surveys(surveys: SurveysDep) -> SurveyList:
    """The surveys this hub is following (planned, flying, or awaiting a hand-over)."""
    return SurveyList(surveys=[surveys.update_of(run) for run in surveys.active()])


@router.get(
    "/surveys/{survey_id:survey_id}",
    response_model=SurveyDetail,
    openapi_extra=requires(Permission.READ),
)
async def get_survey(survey_id: SurveyIdPath, surveys: SurveysDep) -> SurveyDetail:
    return _detail(surveys, await surveys.find(survey_id))


@router.get(
    "/surveys/{survey_id}/progress",
    response_model=SurveyUpdate,
    openapi_extra=requires(Permission.READ),
)
async def survey_progress(survey_id: SurveyIdPath, surveys: SurveysDep) -> SurveyUpdate:
    """Lanes flown, photos taken and the area their footprints cover, overall and per
    drone; the live feed carries the same as `survey` messages."""
    return surveys.update_of(await surveys.find(survey_id))


@router.post(
    "/surveys/{survey_id}/start",
    response_model=SurveyDetail,
    openapi_extra=requires(Permission.COMMAND),
)
async def start_survey(
    survey_id: SurveyIdPath, principal: CurrentPrincipal, surveys: SurveysDep
) -> SurveyDetail:
    """Upload every drone's mission (each checked again on the way), then start them
    together as QGroundControl starts a mission: ArduPilot a guided take-off, then AUTO;
    PX4 its mission mode (MISSION), then arm. An upload refused anywhere starts nothing
    (409); a drone that fails to start (named in its reason) drops out, is disarmed if
    it is still on the ground, and its lanes are offered."""
    return _detail(surveys, await surveys.start(survey_id, principal))


@router.get(
    "/surveys/{survey_id}/handover",
    response_model=HandoverOffer | None,
    openapi_extra=requires(Permission.READ),
)
async def handover_offer(survey_id: SurveyIdPath, surveys: SurveysDep) -> HandoverOffer | None:
    """The hand-over on offer, if any: which drone dropped out and why, and per drone still
    flying its new mission (from where it is) and the time it needs to finish."""
    return (await surveys.find(survey_id)).offer


@router.post(
    "/surveys/{survey_id}/handover/accept",
    response_model=SurveyDetail,
    openapi_extra=requires(Permission.COMMAND),
)
async def accept_handover(
    survey_id: SurveyIdPath, principal: CurrentPrincipal, surveys: SurveysDep
) -> SurveyDetail:
    """Upload the offered missions; each drone flies on from where it is."""
    return _detail(surveys, await surveys.accept(survey_id, principal))


@router.post(
    "/surveys/{survey_id}/vehicles/{vehicle_id}/abort",
    response_model=SurveyDetail,
    openapi_extra=requires(Permission.COMMAND),
)
async def abort_vehicle(
    survey_id: SurveyIdPath,
    vehicle_id: Annotated[VehicleId, Path()],
    principal: CurrentPrincipal,
    surveys: SurveysDep,
) -> SurveyDetail:
    """Take one drone out of the survey: it returns to launch, and its unflown lanes are
    offered to the others."""
    return _detail(surveys, await surveys.drop_vehicle(survey_id, vehicle_id, principal))


@router.post(
    "/surveys/{survey_id}/abort",
    response_model=SurveyDetail,
    openapi_extra=requires(Permission.COMMAND),
)
async def abort_survey(
    survey_id: SurveyIdPath, principal: CurrentPrincipal, surveys: SurveysDep
) -> SurveyDetail:
    """End the survey: every drone still flying it returns to launch."""
    return _detail(surveys, await surveys.abort(survey_id, principal))


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
    body: SurveyFile, principal: CurrentPrincipal, surveys: SurveysDep
) -> Response:
    """A survey request's fields from another tool's file (no side effects): at least the
    `area`, and from a QGC Survey also its camera and settings. Add `vehicle_ids` (and
    anything to change) and send it to `POST /surveys` or the preview. It needs the
    planning permission (as the preview does), and is bounded: the file's size (413) and
    its polygon's vertices (422), and `survey_imports_per_minute` per user (429)."""
    content = await surveys.import_area(principal, body.format, body.content)
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
    surveys: SurveysDep,
    format: Annotated[MissionFormat, Query()] = "plan",
) -> Response:
    """One drone's survey mission as a file other tools open: a QGroundControl `.plan`,
    a `QGC WPL 110` waypoint file (Mission Planner, MAVProxy), or its path as GeoJSON."""
    content = await surveys.mission_file(survey_id, vehicle_id, format)
    name = f"survey-{survey_id}-{vehicle_id}"
    suffix = {"plan": "plan", "wpl": "waypoints", "geojson": "geojson"}[format]
    headers = {"Content-Disposition": f'attachment; filename="{name}.{suffix}"'}
    if isinstance(content, str):
        return PlainTextResponse(content, headers=headers)
    return JSONResponse(content, headers=headers)
