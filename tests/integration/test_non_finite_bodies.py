"""NaN and Infinity are not JSON numbers: a body holding one gets a 422 that names where it
is (and that can itself be serialised), never a 500. Bodies the parser cannot read at all
are 422 too, like any other unparsable body."""

from __future__ import annotations

from collections.abc import Callable

import httpx
import pytest

from tests.support.agents import scripted_agent
from tests.support.api import api_client

Enrol = Callable[[str], str]
JSON = {"Content-Type": "application/json"}


def _refused(response: httpx.Response, location: list[object]) -> None:
    assert response.status_code == 422, response.text
    detail = response.json()["detail"]
    assert [item["loc"] for item in detail] == [location]
    assert "finite number" in detail[0]["msg"]


@pytest.mark.parametrize("constant", ["NaN", "Infinity", "-Infinity"])
def test_non_finite_numbers_are_refused_naming_the_field(
    hub: str, enrol: Enrol, admin_token: str, constant: str
) -> None:
    with scripted_agent(hub, "v1", enrol("v1")), api_client(hub, admin_token) as api:
        param = api.put(
            "/api/v1/vehicles/v1/params/WPNAV_SPEED",
            content=f'{{"value": {constant}}}',
            headers=JSON,
        )
        _refused(param, ["body", "value"])
        takeoff = api.post(
            "/api/v1/vehicles/v1/commands",
            content=f'{{"name": "takeoff", "altitude": {constant}}}',
            headers=JSON,
        )
        _refused(takeoff, ["body", "altitude"])
        mission = api.post(
            "/api/v1/vehicles/v1/mission",
            content=f'{{"items": [{{"command": 16, "x": 1, "y": {constant}}}]}}',
            headers=JSON,
        )
        _refused(mission, ["body", "items", 0, "y"])


@pytest.mark.parametrize(
    "body",
    [b"[" * 30_000, b'{"value": ' + b"9" * 5_000 + b"}", b'{"value": "\xff"}'],
    ids=["deep nesting", "huge integer", "not utf-8"],
)
def test_unparsable_bodies_are_422(hub: str, admin_token: str, body: bytes) -> None:
    with api_client(hub, admin_token) as api:
        response = api.put("/api/v1/vehicles/v1/params/WPNAV_SPEED", content=body, headers=JSON)
    assert response.status_code == 422, response.text
    assert response.json()["detail"][0]["loc"] == ["body"]


@pytest.mark.parametrize("wrong", [False, True, "5"], ids=["false", "true", "numeric string"])
def test_a_number_given_as_a_boolean_or_a_string_is_refused_naming_the_field(
    hub: str, enrol: Enrol, admin_token: str, wrong: object
) -> None:
    """Lax validation took `false` for 0 and "5" for 5: a site's battery reserve of 0 %
    from a client's type mistake. Numbers, integers and booleans are JSON's own."""
    with scripted_agent(hub, "v1", enrol("v1")), api_client(hub, admin_token) as api:
        rails = api.put("/api/v1/safety/rails", json={"battery_reserve_pct": wrong})
        assert rails.status_code == 422, rails.text
        assert [item["loc"] for item in rails.json()["detail"]] == [["body", "battery_reserve_pct"]]
        assert api.get("/api/v1/safety/rails").json()["battery_reserve_pct"] > 0
        takeoff = api.post(
            "/api/v1/vehicles/v1/commands", json={"name": "takeoff", "altitude": wrong}
        )
        assert takeoff.status_code == 422, takeoff.text
        assert ["body", "takeoff", "altitude"] in [item["loc"] for item in takeoff.json()["detail"]]
        # lat and lon as whole numbers are numbers still: only command and autocontinue
        item = {"command": True if wrong == "5" else wrong, "lat": 1, "lon": 1, "autocontinue": 1}
        mission = api.post("/api/v1/vehicles/v1/mission-check", json={"items": [item]})
        assert mission.status_code == 422, mission.text
        assert {tuple(i["loc"]) for i in mission.json()["detail"]} == {
            ("body", "items", 0, "command"),
            ("body", "items", 0, "autocontinue"),
        }


# Every route whose body reaches a vehicle (or a formation of them), with the field the
# number is put in and where the 422 must say it is.
VEHICLE_BODIES = [
    ("PUT", "/api/v1/vehicles/v1/params/WPNAV_SPEED", '{{"value": {n}}}', ["value"]),
    (
        "POST",
        "/api/v1/vehicles/v1/commands",
        '{{"name": "takeoff", "altitude": {n}}}',
        ["altitude"],
    ),
    (
        "POST",
        "/api/v1/vehicles/v1/commands",
        '{{"name": "goto", "lat": 1, "lon": {n}, "alt": 10}}',
        ["lon"],
    ),
    (
        "POST",
        "/api/v1/vehicles/v1/mission",
        '{{"items": [{{"command": 16, "x": 1, "y": {n}}}]}}',
        ["items", 0, "y"],
    ),
    ("PUT", "/api/v1/vehicles/v1/mission/current", '{{"seq": {n}}}', ["seq"]),
    (
        "POST",
        "/api/v1/fleet/commands",
        '{{"command": {{"name": "change_speed", "speed": {n}}}}}',
        ["command", "speed"],
    ),
    (
        "POST",
        "/api/v1/vehicles/v1/mission-check",
        '{{"items": [{{"command": 16, "x": {n}, "y": 1}}]}}',
        ["items", 0, "x"],
    ),
    ("POST", "/api/v1/vehicles/v1/goto-check", '{{"lat": {n}, "lon": 1}}', ["lat"]),
    (
        "POST",
        "/api/v1/formations",
        '{{"route": [{{"lat": 1, "lon": 1, "alt_m": {n}}}], "speed_ms": 2}}',
        ["route", 0, "alt_m"],
    ),
    ("PATCH", "/api/v1/formations/formation-1", '{{"spacing_m": {n}}}', ["spacing_m"]),
]


@pytest.mark.parametrize(
    "number", ["1e309", "-1e309", "1E400", "1.5e999", "NaN", "Infinity", "-Infinity"]
)
def test_a_number_too_large_for_a_float_is_refused_naming_the_field_on_every_vehicle_route(
    hub: str, enrol: Enrol, admin_token: str, number: str
) -> None:
    """1e309 is valid JSON syntax but no double: Python reads it as infinity, which passed
    the NaN/Infinity check and broke the answer (a 500). Refused like NaN, by location."""
    with scripted_agent(hub, "v1", enrol("v1")), api_client(hub, admin_token) as api:
        for method, path, body, where in VEHICLE_BODIES:
            response = api.request(method, path, content=body.format(n=number), headers=JSON)
            _refused(response, ["body", *where])
            assert response.json()["detail"][0]["input"] == number, (path, response.text)
