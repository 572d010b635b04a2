"""Hub -> clients: an area survey's progress."""

from __future__ import annotations

from typing import Literal

from pydantic import Field

from protocol.messages.base import Message, Name, VehicleId


class SurveyDroneProgress(Message):
    vehicle_id: VehicleId
    state: Name = Field(description="assigned, flying, done or dropped")
    lanes_done: int = Field(ge=0)
    lanes_total: int = Field(ge=0)
    photos: int = Field(ge=0)
    reason: str | None = Field(default=None, max_length=500, description="why it dropped out")


class SurveyUpdate(Message):
    """An area survey's progress, at most one a second per survey (newest wins): lanes
    flown, photos triggered (CAMERA_FEEDBACK) and the share of the area their footprints
    cover, overall and per drone, and whether a hand-over awaits the operator."""

    type: Literal["survey"] = "survey"
    survey_id: Name
    state: Name = Field(description="planned, flying, handover_offered, done, aborted, failed")
    lanes_done: int = Field(ge=0)
    lanes_total: int = Field(ge=0)
    photos: int = Field(ge=0)
    covered_pct: float = Field(ge=0, le=100)
    drones: list[SurveyDroneProgress] = Field(max_length=64)
    handover_lanes: int | None = Field(
        default=None, ge=0, description="lanes a hand-over offers to move; null if none offered"
    )
