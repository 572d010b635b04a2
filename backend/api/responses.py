"""What each route can answer besides success, written into the OpenAPI document.

The rules follow from where errors arise, so a new route is documented by them:
- a route behind a permission: 401, 403, and 503 (its token is looked up in the database);
- a route with parameters or a body: 422 (the body names each field and rule);
- a path parameter, or a ``vehicle_id`` query: 404;
- a request body: 413.
``ROUTE_STATUSES`` adds what only some routes do: talk to a vehicle (409 offline or
refused, 504 no answer in time, 429 over the caller's budget of requests to vehicles),
rate limits (429), conflicts (409). ``BEYOND_SCHEMA`` lists the 422s a request the schema
allows can still get (rules across fields, or against the fleet as it is).
"""

from __future__ import annotations

import re
from collections.abc import Iterable
from typing import Any

from fastapi import APIRouter, FastAPI
from fastapi.dependencies.utils import get_flat_params
from fastapi.openapi.utils import get_openapi
from fastapi.routing import APIRoute
from pydantic import BaseModel, ConfigDict, Field

from backend.api.security import PERMISSION_KEY
from backend.auth.policy import PUBLIC, USER_SCOPES


class ErrorMessage(BaseModel):
    """Every error but a 422: one sentence that names what went wrong."""

    detail: str


class ValidationProblem(BaseModel):
    model_config = ConfigDict(extra="allow")  # FastAPI adds input and ctx

    loc: list[str | int] = Field(description="Where: body, query or path, then the field")
    msg: str = Field(description="The rule the value broke")
    type: str


class Unprocessable(BaseModel):
    """A value the route cannot take (``detail`` lists each problem, naming its field and
    rule), or a command or mission the safety rails refuse (``detail`` says so in one
    sentence and ``violations`` lists every violated rule)."""

    detail: str | list[ValidationProblem]
    violations: list[dict[str, Any]] | None = None


RETRY_AFTER = {"Retry-After": {"description": "Seconds to wait", "schema": {"type": "integer"}}}

STATUSES: dict[int, dict[str, Any]] = {
    401: {"description": "Not authenticated, or the token is invalid, expired or revoked"},
    403: {"description": "The role or token lacks the permission this route needs"},
    404: {"description": "No such vehicle, flight, log, user or token (named in the message)"},
    409: {
        "description": "The vehicle is not connected, its flight controller refused, "
        "or the resource exists"
    },
    413: {"description": "The request body is over the size limit"},
    422: {
        "description": "A value the route cannot take (each field and rule named), or a "
        "command refused by the safety rails (every rule listed)",
        "model": Unprocessable,
    },
    429: {
        "description": "Too many attempts, or too many requests to vehicles (commands, "
        "parameters, missions share one budget per user); try again after Retry-After seconds",
        "headers": RETRY_AFTER,
    },
    503: {
        "description": "The database is unavailable; try again after Retry-After seconds",
        "headers": RETRY_AFTER,
    },
    504: {"description": "The agent or the flight controller did not answer in time"},
}

VEHICLE_LINK = frozenset({409, 429, 504})
# (path pattern, methods or None for all, statuses) for what the rules cannot see.
ROUTE_STATUSES: list[tuple[str, frozenset[str] | None, frozenset[int]]] = [
    (
        r"/vehicles/\{vehicle_id\}/(commands|params(/\{param\})?|mission(/current)?)",
        None,
        VEHICLE_LINK,
    ),
    (
        r"(/vehicles/\{vehicle_id\})?/commands|/fleet/commands",
        frozenset({"POST"}),
        frozenset({429}),
    ),
    (r"/fleet/commands", frozenset({"POST"}), frozenset({404})),
    (r"/auth/(login|token)", frozenset({"POST"}), frozenset({401, 429, 503})),
    (r"/users", frozenset({"POST"}), frozenset({409})),
    (r"/vehicles/\{vehicle_id\}/tlogs", frozenset({"POST"}), frozenset({413})),
    # A photo's chunk: at another offset than the hub's (409), over the size (413).
    (r"/vehicles/\{vehicle_id\}/photos/\{photo_id\}", frozenset({"PUT"}), frozenset({409, 413})),
    # A member that is unknown (404) or not connected (409); a formation that stopped (409).
    (r"/formations", frozenset({"POST"}), frozenset({404, 409})),
    (r"/formations/\{formation_id\}(/stop)?", frozenset({"PATCH", "POST"}), frozenset({409})),
    # Survey plans: too many at once (429); area files: too many per user (429).
    (r"/surveys(/preview|/import)?", frozenset({"POST"}), frozenset({429})),
]


# Rules a request can break though the schema lets it through: rules across fields, or
# against the fleet and the data as they are now, which JSON Schema cannot state. Each is
# written into its operation's description and 422 response, and the operation carries
# REFUSES_VALID, which tests/fuzz/schemathesis.toml selects to take a 422 as a documented
# answer to schema-valid data there (and only there). A rule the schema can state belongs
# in the model instead (bounds, patterns, enums, oneOf).
REFUSES_VALID = "x-refuses-schema-valid-requests"
TIME_RANGE_RULE = (
    "`start` after `end`, or a date-time outside the Unix seconds the range allows (from 1970)"
)
RAILS_RULE = (
    "a command the safety rails refuse, for the vehicle's state, mission and rails as they "
    "are now (`violations` lists every rule)"
)
# (path pattern, methods or None for all, rule) for the routes' own rules; routes with
# both `start` and `end` query parameters get TIME_RANGE_RULE from _rules.
BEYOND_SCHEMA: list[tuple[str, frozenset[str] | None, str]] = [
    (r"/telemetry/series", None, "a range (`end` - `start`) over 7 days"),
    (
        r"/mosaics/\{survey_id\}/tiles/\{z\}/\{x\}/\{y\}",
        None,
        "`x` or `y` not below 2**`z` (no such tile in the grid)",
    ),
    (r"/fleet/commands", frozenset({"POST"}), "a `vehicle_ids` entry the hub does not know"),
    (r"/vehicles/\{vehicle_id\}/commands", frozenset({"POST"}), RAILS_RULE),
    (
        r"/vehicles/\{vehicle_id\}/commands",
        frozenset({"POST"}),
        "`set_mode` to a mode the vehicle does not report, or to the mission mode with no "
        "mission on board or one that fails the mission check; `mission_set_current` "
        "beyond the mission on board",
    ),
    (
        r"/vehicles/\{vehicle_id\}/mission",
        frozenset({"POST"}),
        "an item whose MAV_CMD is unknown or lacks what it needs (rule `mission_item`), or "
        "that breaks the safety rails; an altitude above sea level before the vehicle has "
        "reported home's",
    ),
    (
        r"/vehicles/\{vehicle_id\}/mission/current",
        frozenset({"PUT"}),
        "a `seq` that is not an item of the mission on board",
    ),
    (
        r"/surveys(/preview)?",
        frozenset({"POST"}),
        "`vehicle_ids` naming a vehicle twice, or one the hub does not know, has no "
        "position or home yet, or (`POST /surveys` only) is not connected, not ready, "
        "flying or busy in another survey; an `area` the planner cannot cover (rings not "
        "closed, crossing edges, over its size limits); a `camera` that names no preset; "
        "(`POST /surveys` only) a drone's mission the safety rails refuse (`violations` "
        "lists every rule)",
    ),
    (
        r"/surveys/import",
        frozenset({"POST"}),
        "`content` that is not a file of the named `format` holding an area",
    ),
    (
        r"/surveys/\{survey_id\}/vehicles/\{vehicle_id\}/mission",
        frozenset({"GET"}),
        "a `vehicle_id` that is not one of the survey's drones",
    ),
    (r"/users", frozenset({"POST"}), "a `password` that is easy to guess"),
    (
        r"/vehicles/\{vehicle_id\}/tlogs",
        frozenset({"POST"}),
        "a body that is not a MAVLink telemetry log (no complete MAVLink frame)",
    ),
    (
        r"/vehicles/\{vehicle_id\}/photos/\{photo_id\}",
        frozenset({"PUT"}),
        "a first chunk (`offset` 0) without the photo's metadata in `X-Photo-Meta`, or "
        "metadata, image or survey the photo checks refuse (`code` names which)",
    ),
    (
        r"(/vehicles/\{vehicle_id\})?/safety-rails|/safety/rails",
        frozenset({"PUT"}),
        "`min_altitude_m` above `max_altitude_m`; a geofence polygon with fewer than 3 "
        "distinct vertices, crossing edges, or a vertex over 100 km from its centre",
    ),
]


def _rules(route: APIRoute) -> list[str]:
    """The rules beyond the schema that this route refuses with 422."""
    names = {param.name for param in get_flat_params(route.dependant)}
    rules = [TIME_RANGE_RULE] if {"start", "end"} <= names else []
    rules += [rule for pattern, methods, rule in BEYOND_SCHEMA if _is(route, pattern, methods)]
    return rules


def _is(route: APIRoute, pattern: str, methods: frozenset[str] | None) -> bool:
    """Whether ``route`` is one a table's row names (its path, and its method if given)."""
    return re.fullmatch(pattern, route.path) is not None and (
        methods is None or bool((route.methods or set()) & methods)
    )


def _state_rules(route: APIRoute) -> None:
    """Say the route's rules beyond the schema in its description and its 422, and mark it."""
    extra = route.openapi_extra or {}
    rules = _rules(route)
    if not rules or extra.get(REFUSES_VALID):
        return  # none, or said already (the routers outlive one app)
    listed = "".join(f"\n- {rule}" for rule in rules)
    said = f"Refused with 422 though the schema allows it:{listed}"
    route.description = f"{route.description}\n\n{said}".strip()
    refused = route.responses[422]
    refused["description"] = f"{refused['description']}. {said}"
    route.openapi_extra = {**extra, REFUSES_VALID: True}


def _statuses(route: APIRoute) -> set[int]:
    statuses: set[int] = set()
    extra = route.openapi_extra or {}
    if extra.get(PERMISSION_KEY, PUBLIC) != PUBLIC:
        statuses |= {401, 403, 503}
    params = get_flat_params(route.dependant)
    if params or route.body_field is not None:
        statuses.add(422)
    if route.dependant.path_params or any(p.name == "vehicle_id" for p in params):
        statuses.add(404)
    if route.body_field is not None:
        statuses.add(413)
    for pattern, methods, more in ROUTE_STATUSES:
        if _is(route, pattern, methods):
            statuses |= more
    return statuses


def document_errors(app: FastAPI, routers: Iterable[APIRouter]) -> None:
    """Write each route's error statuses, with their body models, into its responses.

    Called on the routers before the app includes them (the app may keep its own
    per-route copies), with their paths as the routers know them (no API prefix)."""
    for router in routers:
        for route in router.routes:
            if isinstance(route, APIRoute) and route.include_in_schema:
                _document(route)
                _state_rules(route)
    app.openapi = lambda: _openapi(app)  # type: ignore[method-assign]


def _document(route: APIRoute) -> None:
    for status in _statuses(route):
        documented = dict(route.responses.get(status, {}))
        default = STATUSES[status]
        documented.setdefault("description", default["description"])
        documented.setdefault("model", default.get("model", ErrorMessage))
        if "headers" in default:
            documented.setdefault("headers", default["headers"])
        route.responses[status] = documented


def _openapi(app: FastAPI) -> dict[str, Any]:
    if app.openapi_schema is None:
        document = get_openapi(
            title=app.title,
            version=app.version,
            description=app.description,
            routes=app.routes,
        )
        _require_discriminators(document)
        _name_required_scopes(document)
        app.openapi_schema = document
    return app.openapi_schema


def _name_required_scopes(document: dict[str, Any]) -> None:
    """Each operation's security requirement names the scope it needs (its permission),
    so the docs' "Authorize" dialog and generated clients know which scope to ask for."""
    user_scopes = {scope.value for scope in USER_SCOPES}
    for operations in document.get("paths", {}).values():
        for operation in operations.values():
            needed = operation.get(PERMISSION_KEY)
            for requirement in operation.get("security", []):
                for scheme in requirement:
                    requirement[scheme] = [needed] if needed in user_scopes else []


def _require_discriminators(document: dict[str, Any]) -> None:
    """A tagged union's tag is required on the wire (pydantic cannot pick a member without
    it), though each member's model gives it a default; say so in each member's schema."""
    schemas = document.get("components", {}).get("schemas", {})

    def visit(node: object) -> None:
        if isinstance(node, dict):
            discriminator = node.get("discriminator")
            if isinstance(discriminator, dict):
                tag = discriminator["propertyName"]
                for ref in discriminator.get("mapping", {}).values():
                    member = schemas.get(ref.rsplit("/", 1)[-1])
                    if member is not None and tag not in member.get("required", []):
                        member["required"] = [tag, *member.get("required", [])]
            for value in node.values():
                visit(value)
        elif isinstance(node, list):
            for value in node:
                visit(value)

    visit(document)
