from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import pytest
from pydantic import ValidationError

from backend.safety import SafetyRails, evaluate_plan
from backend.safety.mission_schemas import Mission, MissionCheckResponse
from backend.safety.schemas import GeofenceModel, SafetyRailsModel
from protocol.messages import MissionItem
from tests.unit.safety.shapes import U_SHAPE, geo, u_fence, vehicle, wp


def polygon(points: Sequence[tuple[float, float]]) -> list[dict[str, float]]:
    return [{"lat": p.lat, "lon": p.lon} for p in (geo(e, n) for e, n in points)]


def rails_body(**extra: Any) -> dict[str, Any]:
    return {
        "geofence": {"polygon": polygon(U_SHAPE), "max_altitude_m": 100},
        "max_distance_from_home_m": 500,
        "min_altitude_m": 5,
        "max_altitude_m": 120,
        "min_launch_battery_pct": 30,
        **extra,
    }


def errors(exc: pytest.ExceptionInfo[ValidationError]) -> list[tuple[tuple[int | str, ...], str]]:
    return [(e["loc"], e["msg"]) for e in exc.value.errors()]


def test_rails_round_trip() -> None:
    model = SafetyRailsModel.model_validate(rails_body())
    rails = model.to_rails()
    assert rails == SafetyRails(
        geofence=u_fence(max_altitude_m=100),
        max_distance_from_home_m=500,
        min_altitude_m=5,
        max_altitude_m=120,
        min_launch_battery_pct=30,
        battery_reserve_pct=20,
    )
    again = SafetyRailsModel.from_rails(rails)
    assert again == model
    assert SafetyRailsModel.model_validate_json(again.model_dump_json()).to_rails() == rails


def test_empty_rails_are_all_unset_with_the_default_reserve() -> None:
    assert SafetyRailsModel().to_rails() == SafetyRails()


def test_closing_vertex_is_dropped() -> None:
    ring = polygon([(0, 0), (100, 0), (0, 100), (0, 0)])
    assert len(GeofenceModel.model_validate({"polygon": ring}).polygon) == 3


@pytest.mark.parametrize(
    ("body", "loc", "reason"),
    [
        (
            rails_body(geofence={"polygon": polygon([(0, 0), (100, 100), (100, 0), (0, 100)])}),
            ("geofence", "polygon"),
            "edges 1 and 3 cross",
        ),
        (
            rails_body(geofence={"polygon": polygon([(0, 0), (100, 100)])}),
            ("geofence", "polygon"),
            "fewer than 3 distinct vertices",
        ),
        (
            rails_body(geofence={"polygon": [{"lat": 91, "lon": 8}, *polygon(U_SHAPE)]}),
            ("geofence", "polygon", 0, "lat"),
            "less than or equal to 90",
        ),
        (rails_body(max_altitude_m=20_000), ("max_altitude_m",), "less than or equal to 10000"),
        (rails_body(min_launch_battery_pct=101), ("min_launch_battery_pct",), "100"),
        (rails_body(battery_reserve_pct=-1), ("battery_reserve_pct",), "greater than or equal"),
        (rails_body(max_altitude_m=float("nan")), ("max_altitude_m",), "finite number"),
        (rails_body(max_altitude_m="50"), ("max_altitude_m",), "valid number"),
        (rails_body(max_altitude=50), ("max_altitude",), "Extra inputs are not permitted"),
        (rails_body(min_altitude_m=200), (), "min_altitude_m 200.0 m is above max_altitude_m"),
    ],
)
def test_invalid_rails_name_the_field_and_the_problem(
    body: dict[str, Any], loc: tuple[int | str, ...], reason: str
) -> None:
    with pytest.raises(ValidationError) as caught:
        SafetyRailsModel.model_validate(body)
    [(where, message)] = errors(caught)
    assert where == loc
    assert reason in message


def test_mission_bounds() -> None:
    one = {"command": 16, "lat": 47.0, "lon": 8.0, "alt": 30}
    assert Mission.model_validate({"items": [one]}).items == [MissionItem.model_validate(one)]
    for count in (0, 2001):
        with pytest.raises(ValidationError) as caught:
            Mission.model_validate({"items": [one] * count})
        assert errors(caught)[0][0] == ("items",)
    with pytest.raises(ValidationError) as caught:
        Mission.model_validate({"items": [{**one, "lat": 91}]})
    assert errors(caught)[0][0] == ("items", 0, "lat")


def test_mission_response_from_a_plan_check() -> None:
    rails = SafetyRails(geofence=u_fence())
    check = evaluate_plan(rails, vehicle(), [wp(50, 250, 30), wp(250, 250, 30)])
    body = MissionCheckResponse.from_plan_check(check).model_dump(mode="json")
    assert body["ok"] is False
    assert body["violations"] == [
        {
            "rule": "geofence",
            "message": "the leg from waypoint 1 to waypoint 2 leaves the geofence",
            "limit": None,
            "value": None,
            "items": [],
        }
    ]
    assert body["estimate"]["available_pct"] == 90
    assert body["estimate"]["required_pct"] > 0
    unknown = MissionCheckResponse.build([], None)
    assert unknown.ok
    assert unknown.estimate is None


# The hub's pinned Starlette prefers a successor to httpx; the test client still works.
@pytest.mark.filterwarnings("ignore:Using `httpx` with `starlette.testclient`")
def test_fastapi_answers_422_naming_the_polygon() -> None:
    pytest.importorskip("fastapi")
    from fastapi import FastAPI
    from fastapi.testclient import TestClient

    app = FastAPI()

    @app.put("/rails")
    def put_rails(body: SafetyRailsModel) -> SafetyRailsModel:
        return body

    client = TestClient(app)
    bow_tie = rails_body(geofence={"polygon": polygon([(0, 0), (100, 100), (100, 0), (0, 100)])})
    response = client.put("/rails", json=bow_tie)
    assert response.status_code == 422
    [detail] = response.json()["detail"]
    assert detail["loc"] == ["body", "geofence", "polygon"]
    assert "edges 1 and 3 cross" in detail["msg"]
    assert client.put("/rails", json=rails_body()).status_code == 200
