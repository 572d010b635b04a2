"""Requests the OpenAPI document allows are ones the hub takes, or the document says why
not: a rule the schema can state is in the schema (the REST commands leave out the lease's
own, a survey gives exactly one of altitude and GSD); a rule across fields or against the
fleet as it is (start after end, a command the rails refuse) is listed in the operation's
description and 422 response, and the operation is marked for the fuzzer's config
(tests/fuzz/schemathesis.toml), which then takes a 422 there and nowhere else."""

from __future__ import annotations

import tomllib
from pathlib import Path
from typing import Any

import jsonschema_rs
import pytest
from pydantic import TypeAdapter, ValidationError

from backend.api.responses import REFUSES_VALID
from backend.openapi_document import openapi_document
from protocol.messages import LEASE_COMMANDS, ClientCommand

FUZZ_CONFIG = Path(__file__).parents[2] / "fuzz" / "schemathesis.toml"
SAID = "Refused with 422 though the schema allows it:"
# What schemathesis, with every check and no allowance, found refused (the item 10).
FOUND_BY_THE_FUZZER = {
    ("get", "/api/v1/commands"),
    ("get", "/api/v1/events"),
    ("get", "/api/v1/telemetry/series"),
    ("get", "/api/v1/vehicles/{vehicle_id}/scans"),
    ("get", "/api/v1/vehicles/{vehicle_id}/telemetry"),
    ("get", "/api/v1/mosaics/{survey_id}/tiles/{z}/{x}/{y}"),
    ("post", "/api/v1/fleet/commands"),
    ("post", "/api/v1/vehicles/{vehicle_id}/commands"),
    ("post", "/api/v1/vehicles/{vehicle_id}/mission"),
    ("put", "/api/v1/vehicles/{vehicle_id}/mission/current"),
    ("post", "/api/v1/surveys"),
    ("post", "/api/v1/surveys/preview"),
    ("post", "/api/v1/surveys/import"),
    ("post", "/api/v1/users"),
    ("put", "/api/v1/safety/rails"),
    ("put", "/api/v1/vehicles/{vehicle_id}/safety-rails"),
    ("post", "/api/v1/vehicles/{vehicle_id}/tlogs"),
    ("put", "/api/v1/vehicles/{vehicle_id}/photos/{photo_id}"),
}


@pytest.fixture(scope="module")
def document() -> dict[str, Any]:
    openapi_document()  # a first app documents the routers; the second must not say it twice
    return openapi_document()


def _operations(document: dict[str, Any]) -> dict[tuple[str, str], dict[str, Any]]:
    return {
        (method, path): operation
        for path, operations in document["paths"].items()
        for method, operation in operations.items()
    }


def _validator(document: dict[str, Any], schema: dict[str, Any]) -> Any:
    return jsonschema_rs.validator_for({**schema, "components": document["components"]})


def test_each_rule_beyond_the_schema_is_said_where_a_client_reads_it(
    document: dict[str, Any],
) -> None:
    operations = _operations(document)
    marked = {key for key, operation in operations.items() if operation.get(REFUSES_VALID)}
    assert marked >= FOUND_BY_THE_FUZZER, FOUND_BY_THE_FUZZER - marked
    for key, operation in operations.items():
        refused = operation.get("responses", {}).get("422", {}).get("description", "")
        if key in marked:
            # Said once (the routers outlive an app, and each app documents them again).
            assert operation["description"].count(SAID) == 1, key
            assert refused.count(SAID) == 1, key
            assert refused.split(SAID)[1].strip().startswith("- "), key
        else:
            assert SAID not in operation.get("description", "") + refused, key


def test_every_bound_is_one_json_schema_knows(document: dict[str, Any]) -> None:
    """pydantic writes a bound it applies around a validator as "ge"/"le", which JSON
    Schema ignores: the fuzzer then sends 6153469 days to a field that takes 3650."""
    misnamed: list[str] = []

    def walk(node: object, where: str) -> None:
        if isinstance(node, dict):
            if "type" in node and {"ge", "le", "gt", "lt"} & set(node):
                misnamed.append(where)
            for key, value in node.items():
                walk(value, f"{where}/{key}")
        elif isinstance(node, list):
            for index, value in enumerate(node):
                walk(value, f"{where}/{index}")

    walk(document, "")
    assert misnamed == []


def test_the_fuzzer_takes_a_422_only_where_the_schema_says_so() -> None:
    config = tomllib.loads(FUZZ_CONFIG.read_text())
    assert "positive_data_acceptance" not in config.get("checks", {})  # no global allowance
    allowing = [
        operation
        for operation in config["operations"]
        if "422"
        in operation.get("checks", {})
        .get("positive_data_acceptance", {})
        .get("expected-statuses", [])
    ]
    assert [operation["include-by"] for operation in allowing] == [f"/{REFUSES_VALID} == true"]


def test_the_rest_commands_leave_out_the_leases_own(document: dict[str, Any]) -> None:
    body = document["paths"]["/api/v1/vehicles/{vehicle_id}/commands"]["post"]["requestBody"]
    schema = body["content"]["application/json"]["schema"]
    assert not LEASE_COMMANDS & set(schema["discriminator"]["mapping"])
    assert "arm" in schema["discriminator"]["mapping"]
    group = document["components"]["schemas"]["GroupCommandRequest"]["properties"]["command"]
    assert not LEASE_COMMANDS & set(group["discriminator"]["mapping"])
    commands = TypeAdapter(ClientCommand)
    for name in LEASE_COMMANDS:
        with pytest.raises(ValidationError, match="comes with the manual-control lease"):
            commands.validate_python({"name": name})
    # A name that is not a string is a 422 like any other (it was a 500 once).
    with pytest.raises(ValidationError):
        commands.validate_python({"name": {}, "seq": 1})


@pytest.mark.parametrize(
    ("heights", "valid"),
    [
        ({"altitude_m": 50}, True),
        ({"gsd_cm": 2.5}, True),
        ({"altitude_m": 50, "gsd_cm": None}, True),  # as the dashboard sends it
        ({"altitude_m": None, "gsd_cm": 2.5}, True),
        ({"altitude_m": 50, "gsd_cm": 2.5}, False),
        ({}, False),
        ({"altitude_m": None, "gsd_cm": None}, False),
    ],
)
def test_a_survey_gives_exactly_one_height_in_its_schema(
    document: dict[str, Any], heights: dict[str, Any], valid: bool
) -> None:
    body = {
        "area": {"type": "Polygon", "coordinates": [[[0, 0], [0, 1], [1, 1], [0, 0]]]},
        "camera": "sony_a6000_16mm",
        "vehicle_ids": ["sim_1"],
        **heights,
    }
    schema = {"$ref": "#/components/schemas/SurveyRequest"}
    assert _validator(document, schema).is_valid(body) is valid
