"""REST bodies of the survey preview: what to plan, and the plan with one mission per drone.

Unknown fields, NaN and infinities are rejected, as for the missions' bodies.
"""

from __future__ import annotations

from typing import Annotated, Any, Literal

from pydantic import BaseModel, ConfigDict, Discriminator, Field, Tag, model_validator
from pydantic.config import JsonDict

from backend.safety.mission_schemas import Mission, MissionCheckResponse
from protocol.messages import Boolean, Integer, Number, VehicleId


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", allow_inf_nan=False)


class GeoJsonPolygon(_Strict):
    type: Literal["Polygon"]
    coordinates: list[list[list[Number]]] = Field(
        min_length=1,
        description="[longitude, latitude] rings: the outline first, then holes (no-fly areas)",
    )


class CameraModel(_Strict):
    sensor_width_mm: Number = Field(gt=0, le=100)
    sensor_height_mm: Number = Field(gt=0, le=100)
    image_width_px: Integer = Field(gt=0, le=100_000)
    image_height_px: Integer = Field(gt=0, le=100_000)
    focal_length_mm: Number = Field(gt=0, le=1000)
    landscape: Boolean = True
    distance_trigger: Boolean = True


class ManualCamera(_Strict):
    """QGroundControl's "Manual (no camera specs)": no sensor figures, the lanes' spacing and
    the distance between photos given directly (its AdjustedFootprintSide and
    AdjustedFootprintFrontal), flown at altitude_m (a GSD cannot be computed)."""

    lane_spacing_m: Number = Field(gt=0, le=1000, description="Distance between lanes")
    trigger_distance_m: Number = Field(gt=0, le=1000, description="Distance between photos")
    distance_trigger: Boolean = True


def _camera_kind(value: Any) -> str | None:
    """Which of the camera's forms a value is, so a refusal names the fields of that form
    alone (not "Input should be a valid string" from the preset's branch first)."""
    if isinstance(value, str):
        return "preset"
    if isinstance(value, dict):
        return "manual" if "lane_spacing_m" in value or "trigger_distance_m" in value else "model"
    if isinstance(value, ManualCamera):
        return "manual"
    if isinstance(value, CameraModel):
        return "model"
    return None  # pydantic refuses it: "does not match any of the expected tags"


Camera = Annotated[
    Annotated[str, Tag("preset")]
    | Annotated[CameraModel, Tag("model")]
    | Annotated[ManualCamera, Tag("manual")],
    Discriminator(
        _camera_kind,
        custom_error_type="camera_kind",
        custom_error_message="give a preset's name, the camera's figures or a manual camera",
    ),
]


# "Exactly one of altitude_m and gsd_cm" (the validator below), in the schema's words.
_ONE_HEIGHT: JsonDict = {
    "oneOf": [
        {
            "required": [given],
            "properties": {given: {"type": "number"}, other: {"type": "null"}},
        }
        for given, other in (("altitude_m", "gsd_cm"), ("gsd_cm", "altitude_m"))
    ]
}


class SurveyRequest(_Strict):
    model_config = ConfigDict(json_schema_extra=_ONE_HEIGHT)

    area: GeoJsonPolygon
    camera: Camera = Field(
        description="A preset's name (e.g. sony_a6000_16mm), the camera's figures, or a manual "
        "camera (lane spacing and trigger distance, with altitude_m)"
    )
    altitude_m: Number | None = Field(default=None, gt=0, description="Above home; or give gsd_cm")
    gsd_cm: Number | None = Field(
        default=None, gt=0, description="cm per pixel; or give altitude_m"
    )
    side_overlap_pct: Number = Field(default=70.0, ge=0, lt=100)
    front_overlap_pct: Number = Field(default=80.0, ge=0, lt=100)
    angle_deg: Number | None = Field(
        default=None, ge=0, lt=180, description="Lane heading; null chooses the fastest"
    )
    speed_ms: Number = Field(default=10.0, gt=0, le=30)
    turnaround_m: Number = Field(default=10.0, ge=0, le=200)
    hover_and_capture: Boolean = False
    vehicle_ids: list[VehicleId] = Field(min_length=1, max_length=64)

    @model_validator(mode="after")
    def _one_height(self) -> SurveyRequest:
        if (self.altitude_m is None) == (self.gsd_cm is None):
            raise ValueError("give exactly one of altitude_m and gsd_cm")
        if isinstance(self.camera, ManualCamera) and self.altitude_m is None:
            raise ValueError("a manual camera has no sensor to derive a GSD: give altitude_m")
        return self


class SurveyPart(_Strict):
    vehicle_id: str
    mission: Mission
    lanes: int
    photo_count: int
    path_length_m: float
    transit_s: float
    survey_s: float
    home_s: float
    total_s: float = Field(description="Transit to the part, the part, and the way home")
    lane_paths: list[list[list[float]]] = Field(
        description="Each lane's [[lat, lon], [lat, lon]] from start to end, for the map"
    )
    check: MissionCheckResponse


class SurveyPreview(_Strict):
    ok: bool = Field(
        description="True when every part's mission passes the safety rails and each "
        "drone carries the camera the plan assumes (rule survey_camera)"
    )
    altitude_m: float
    gsd_cm: float | None = Field(description="null for a manual camera (no sensor figures)")
    footprint_side_m: float
    footprint_frontal_m: float
    lane_spacing_m: float
    trigger_distance_m: float
    angle_deg: float
    area_m2: float
    coverage_pct: float = Field(description="Area (holes excluded) seen by the photos' footprints")
    coverage_at_overlaps_pct: float = Field(
        description="Area seen with at least the requested side and front overlaps"
    )
    photo_count: int
    lanes: int
    parts: list[SurveyPart]

    def summary(self) -> dict[str, Any]:
        return self.model_dump(exclude={"parts"})
