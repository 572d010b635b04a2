"""Every string, list and map in every wire message has a bound, so that no peer can make
the hub store, or every dashboard receive, more than a message's worth."""

from __future__ import annotations

from typing import Any

import pytest
from pydantic import ValidationError

from protocol.messages import MAX_MODES, MAX_NAME_CHARS, PROTOCOL_VERSION, Hello, json_schema


def _unbounded(schema: Any, where: str, found: list[str]) -> list[str]:
    if isinstance(schema, dict):
        kind = schema.get("type")
        fixed = "const" in schema or "enum" in schema
        if kind == "string" and not fixed and "maxLength" not in schema:
            found.append(where)
        if kind == "array" and "maxItems" not in schema:
            found.append(where)
        if (
            kind == "object"
            and isinstance(schema.get("additionalProperties"), dict)
            and "maxProperties" not in schema
        ):
            found.append(where)
        for key, value in schema.items():
            _unbounded(value, f"{where}.{key}", found)
    elif isinstance(schema, list):
        for index, value in enumerate(schema):
            _unbounded(value, f"{where}[{index}]", found)
    return found


def test_every_string_list_and_map_of_the_protocol_is_bounded() -> None:
    schemas = json_schema()
    found: list[str] = []
    for direction in ("agent_to_hub", "hub_to_agent", "client_to_hub", "hub_to_client"):
        _unbounded(schemas[direction], direction, found)
    assert found == [], "unbounded fields:\n" + "\n".join(found)


def _hello(**changes: Any) -> dict[str, Any]:
    hello = {
        "protocol": PROTOCOL_VERSION,
        "vehicle_id": "v1",
        "autopilot": "ardupilot",
        "vehicle_type": "multirotor",
        "system_id": 1,
        "agent_version": "1",
        "stream_id": "s",
        "modes": ["GUIDED"],
    }
    return {**hello, **changes}


@pytest.mark.parametrize(
    "changes",
    [
        {"modes": [f"MODE_{n}" for n in range(MAX_MODES + 1)]},
        {"modes": ["M" * (MAX_NAME_CHARS + 1)]},
        {"modes": ["X" * 60_000]},
        {"capabilities": ["telemetry"] * 1000},
        {"agent_version": "1" * 1000},
        {"autopilot": "a" * 1000},
    ],
    ids=["65 modes", "a long mode", "60 KB mode", "1000 capabilities", "version", "autopilot"],
)
def test_an_oversized_hello_is_refused(changes: dict[str, Any]) -> None:
    with pytest.raises(ValidationError):
        Hello.model_validate(_hello(**changes))
    assert Hello.model_validate(_hello())
