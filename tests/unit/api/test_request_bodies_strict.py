"""Every number, integer and boolean a route takes in its body is strict: JSON's own
type, never `false` taken for 0 or "5" for 5 (pydantic's lax Python mode, which FastAPI
validates parsed bodies in). A route added with a plain `float` fails here, before the
fuzz run's negative_data_rejection check finds it against a live fleet."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest
from fastapi.routing import APIRoute, iter_route_contexts
from pydantic import BaseModel, TypeAdapter, ValidationError

from backend.app import create_app
from protocol.messages import MissionItem, MissionSetCurrentCommand, Number
from tests.conftest import hub_settings

_SCALARS = {"float", "int", "bool"}


def lax_scalars(annotation: Any) -> list[tuple[object, ...]]:
    """Where, in the core schema of ``annotation``, a number or boolean is not strict."""
    found: list[tuple[object, ...]] = []

    def walk(node: object, path: tuple[object, ...]) -> None:
        if isinstance(node, dict):
            kind = node.get("type")  # (a "fields" mapping may have a field named type)
            if isinstance(kind, str) and kind in _SCALARS and not node.get("strict"):
                found.append(path)
            for key, value in node.items():
                walk(value, (*path, key))
        elif isinstance(node, list):
            for index, value in enumerate(node):
                walk(value, (*path, index))

    walk(TypeAdapter(annotation).core_schema, ())
    return found


def test_the_check_finds_a_lax_number() -> None:
    class Lax(BaseModel):
        altitude: float

    class Strict(BaseModel):
        altitude: Number
        points: list[list[Number]]

    assert lax_scalars(Lax)
    assert not lax_scalars(Strict)


def test_every_request_body_takes_json_numbers_and_booleans_only(tmp_path: Path) -> None:
    app = create_app(hub_settings(tmp_path))
    routes = [context.original_route for context in iter_route_contexts(app.routes)]
    bodies = [r for r in routes if isinstance(r, APIRoute) and r.body_field is not None]
    assert len(bodies) >= 10  # the walk reached the included routers' routes
    lax = {
        f"{sorted(route.methods)} {route.path}": found
        for route in bodies
        if route.body_field is not None
        if (found := lax_scalars(route.body_field.field_info.annotation))
    }
    assert lax == {}


def test_a_whole_number_written_as_a_float_is_that_integer() -> None:
    """JSON has one number type, and JSON Schema's "integer" takes 3.0: a client's float
    arithmetic writing 16.0 for a MAV_CMD means 16 (the fuzzer found such a mission
    refused). A fraction, a boolean or a string is still no integer."""
    item = MissionItem.model_validate({"command": 16.0, "frame": 3.0, "lat": 1.0})
    assert (item.command, item.frame) == (16, 3)
    assert type(item.command) is int
    assert type(item.frame) is int
    assert MissionSetCurrentCommand.model_validate({"seq": 2.0}).seq == 2
    for wrong in (16.5, True, "16", 70_000.0, float("nan")):
        with pytest.raises(ValidationError):
            MissionItem.model_validate({"command": wrong})
