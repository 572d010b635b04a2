"""Area surveys and their photos: when a drone drops out, the planner's bounds, uploads."""

from __future__ import annotations

from pydantic import BaseModel, Field

from protocol.messages import MAX_MISSION_ITEMS


class SurveySettings(BaseModel):
    """Surveys in flight, their planning and imports, and survey photos."""

    survey_link_timeout_s: float = Field(
        default=10.0,
        gt=0,
        le=3600,
        description="a surveying drone whose agent has been gone this long is out of the "
        "survey: its unflown lanes are offered to the others",
    )
    survey_battery_floor_pct: float = Field(
        default=20.0,
        ge=0,
        le=100,
        description="a surveying drone whose battery falls below this is out of the survey",
    )
    photo_survey_margin_m: float = Field(
        default=500.0,
        gt=0,
        description="a photo whose position is further than this outside its survey's area "
        "is refused (a wrong pose, or a photo of another survey)",
    )
    max_photo_bytes_per_vehicle: int = Field(
        default=20 * 1024 * 1024 * 1024,
        ge=1024,
        description="all of one vehicle's stored photos and the declared sizes of its "
        "uploads in progress together; an upload beyond is a 413",
    )
    photo_uploads_per_vehicle: int = Field(
        default=8,
        ge=1,
        le=64,
        description="photo uploads one vehicle may have in progress at once; beyond, 429",
    )
    photo_upload_expiry_s: float = Field(
        default=6 * 3600.0,
        ge=60,
        description="an unfinished photo upload untouched this long is removed",
    )
    survey_update_interval_s: float = Field(
        default=1.0, gt=0, le=60, description="a survey's progress goes out at most this often"
    )
    # Survey planning's bounds (docs/security.md "Survey planning"): a plan is estimated
    # from the area and the camera before it is planned, and refused (422) past these.
    survey_max_lanes: int = Field(
        default=1000, ge=1, description="lanes a survey plan may have (estimated first)"
    )
    survey_max_photos: int = Field(
        default=20_000, ge=1, description="photos a survey plan may take (estimated first)"
    )
    survey_max_mission_items: int = Field(
        default=700,
        ge=10,
        le=MAX_MISSION_ITEMS,
        description="items one drone's survey mission may have: the smallest mission store "
        "in the fleet (ArduPilot on a 16 KB FRAM board holds about 700; an SD card far more)",
    )
    survey_plan_timeout_s: float = Field(
        default=30.0, gt=0, le=600, description="a survey plan still running after this stops"
    )
    survey_plan_workers: int = Field(
        default=2, ge=1, le=32, description="survey plans computed at once (worker processes)"
    )
    survey_plan_max_pending: int = Field(
        default=8, ge=1, description="survey plans running or waiting for a worker; beyond, 429"
    )
    survey_import_max_bytes: int = Field(
        default=1_000_000, ge=1024, description="a survey area file's size (KML, GeoJSON, .plan)"
    )
    survey_import_max_vertices: int = Field(
        default=10_000, ge=4, description="the vertices of a survey area file's polygon"
    )
    survey_import_max_pending: int = Field(
        default=4, ge=1, description="area files being read or waiting (one worker); beyond, 429"
    )
    survey_import_timeout_s: float = Field(
        default=10.0, gt=0, le=600, description="an area file still being read after this stops"
    )
    survey_imports_per_minute: int = Field(
        default=10, ge=1, description="survey area files one user may import per minute"
    )
