"""What happened and what was asked: the event log and the command log, newest first."""

from __future__ import annotations

import asyncio
import json
from typing import Annotated, Any

from fastapi import Query
from pydantic import BaseModel, ConfigDict, Field, field_validator

from backend.api.deps import LogbookDep, RegistryDep
from backend.api.logs.common import MAX_ID, MAX_PAGE, next_before_id
from backend.api.security import SecuredRouter, requires
from backend.api.time_ranges import TimeQuery, optional_time_range
from backend.auth.policy import Permission
from protocol.messages import StoredEventKind

router = SecuredRouter(tags=["flight log"])


class EventRecord(BaseModel):
    model_config = ConfigDict(from_attributes=True)

    id: int
    vehicle_id: str
    time: float
    kind: str
    severity: int | None
    text: str
    mission_item: int | None = None


class EventPage(BaseModel):
    events: list[EventRecord]
    next_before_id: int | None


class CommandRecord(BaseModel):
    model_config = ConfigDict(from_attributes=True)

    id: int
    time: float
    vehicle_id: str
    actor: str
    name: str
    # Stored as JSON text; answered as the object it is, as in the audit log's detail.
    command: dict[str, Any] = Field(
        validation_alias="command_json", description='The command as sent, e.g. {"name": "land"}'
    )
    status: str
    result: str | None
    message: str

    @field_validator("command", mode="before")
    @classmethod
    def _parsed(cls, stored: object) -> object:
        if not isinstance(stored, str):
            return stored
        try:
            value = json.loads(stored)
        except json.JSONDecodeError:
            return {"unparsed": stored}  # cut short at the column's size
        return value if isinstance(value, dict) else {"value": value}


class CommandPage(BaseModel):
    commands: list[CommandRecord]
    next_before_id: int | None


@router.get("/events", response_model=EventPage, openapi_extra=requires(Permission.READ))
async def list_events(
    registry: RegistryDep,
    logbook: LogbookDep,
    vehicle_id: Annotated[str | None, Query(max_length=64)] = None,
    kind: Annotated[StoredEventKind | None, Query(description="One of the kinds listed")] = None,
    start: TimeQuery = None,
    end: TimeQuery = None,
    before_id: Annotated[int | None, Query(ge=1, le=MAX_ID)] = None,
    limit: Annotated[int, Query(ge=1, le=MAX_PAGE)] = 100,
) -> EventPage:
    """STATUSTEXTs, mode changes, arming, failsafes and link changes, newest first."""
    if vehicle_id is not None:
        registry.get(vehicle_id)
    start_at, end_at = optional_time_range(start, end)
    rows = list(
        await asyncio.to_thread(
            logbook.events, vehicle_id, kind, start_at, end_at, before_id, limit
        )
    )
    return EventPage(
        events=[EventRecord.model_validate(row) for row in rows],
        next_before_id=next_before_id(rows, limit),
    )


@router.get("/commands", response_model=CommandPage, openapi_extra=requires(Permission.READ))
async def list_commands(
    registry: RegistryDep,
    logbook: LogbookDep,
    vehicle_id: Annotated[str | None, Query(max_length=64)] = None,
    actor: Annotated[str | None, Query(max_length=80)] = None,
    start: TimeQuery = None,
    end: TimeQuery = None,
    before_id: Annotated[int | None, Query(ge=1, le=MAX_ID)] = None,
    limit: Annotated[int, Query(ge=1, le=MAX_PAGE)] = 100,
) -> CommandPage:
    """Commands sent, who sent them and what the vehicle answered, newest first."""
    if vehicle_id is not None:
        registry.get(vehicle_id)
    start_at, end_at = optional_time_range(start, end)
    rows = list(
        await asyncio.to_thread(
            logbook.commands, vehicle_id, actor, start_at, end_at, before_id, limit
        )
    )
    return CommandPage(
        commands=[CommandRecord.model_validate(row) for row in rows],
        next_before_id=next_before_id(rows, limit),
    )
