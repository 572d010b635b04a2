"""Formation missions as planned: the shape presets and the leader's route, and the
planner's refusals. The follower's rules and the simulator's answer to its targets are
test_follower.py's."""

from __future__ import annotations

import math
from typing import Any

import pytest

from backend.formation import FormationRefused, plan_formation
from backend.formation.route import LeaderRoute
from backend.formation.schemas import FormationRequest
from backend.safety.geofence import Geofence
from backend.safety.rails import SafetyRails
from backend.safety.snapshot import VehicleSnapshot
from common.formation import (
    ConsensusGains,
    Controller,
    LeaderState,
    Offset,
    OffsetFrame,
    Shape,
    shape_offsets,
    slot_target,
)
from common.geodesy import GeoPoint, LocalFrame
from simulator import DEFAULT_HOME

HOME = LocalFrame(DEFAULT_HOME.lat, DEFAULT_HOME.lon)


def _geo(north: float, east: float) -> tuple[float, float]:
    return HOME.to_geo(east, north)


def _snapshot(north: float = 0.0, east: float = 0.0) -> VehicleSnapshot:
    lat, lon = _geo(north, east)
    return VehicleSnapshot(lat, lon, 0.0, lat, lon, 100.0, armed=False, landed=True)


def _request(**overrides: Any) -> FormationRequest:
    route = []
    for north, east in [(0, 0), (20, 0), (20, 20), (0, 20), (0, 0)]:
        lat, lon = _geo(north, east)
        route.append({"lat": lat, "lon": lon, "alt_m": 8.0})
    body: dict[str, Any] = {
        "leader_id": "lead",
        "route": route,
        "speed_ms": 1.5,
        "pause_s": 2.0,
        "followers": [{"vehicle_id": "f1", "up": -6.0}, {"vehicle_id": "f2", "up": -5.0}],
        "shape": "triangle",
        "spacing_m": 3.0,
        "min_separation_m": 2.0,
    }
    body.update(overrides)
    return FormationRequest.model_validate(body)


VEHICLES = {"lead": _snapshot(), "f1": _snapshot(-2, 2), "f2": _snapshot(-2, -2)}


def _plan(request: FormationRequest, **kwargs: Any) -> Any:
    kwargs.setdefault("rails", SafetyRails())
    kwargs.setdefault("vehicles", VEHICLES)
    return plan_formation(request, **kwargs)


# -- geometry ------------------------------------------------------------------


def test_presets_space_their_slots() -> None:
    for shape in Shape:
        slots = shape_offsets(shape, 4, 3.0)
        points = [(0.0, 0.0, 0.0)] + [o.north_east_up(0.0) for o in slots]
        nearest = min(math.dist(a, b) for i, a in enumerate(points) for b in points[i + 1 :])
        assert nearest == pytest.approx(3.0, abs=1e-6) or nearest > 3.0, shape
    # a wedge is behind the leader, right then left
    right, left = shape_offsets(Shape.WEDGE, 2, 3.0)
    assert right.x < 0
    assert right.y > 0
    assert left.y < 0
    with pytest.raises(ValueError, match="spacing"):
        shape_offsets(Shape.LINE, 2, 0.0)


def test_heading_frame_turns_with_the_leader_and_north_east_does_not() -> None:
    behind = Offset(-3.0, 0.0, 1.0)
    assert behind.north_east_up(math.pi / 2) == pytest.approx((0.0, -3.0, 1.0))
    fixed = Offset(-3.0, 0.0, 1.0, OffsetFrame.NORTH_EAST)
    assert fixed.north_east_up(math.pi / 2) == pytest.approx((-3.0, 0.0, 1.0))


def test_the_leader_is_predicted_over_the_link_delay() -> None:
    leader = LeaderState(0.0, 0.0, 8.0, 1.5, 0.0, 0.0, 0.0, time_s=10.0)
    position, velocity = slot_target(leader.predicted(10.2), Offset(-2.0, 0.0, -6.0))
    assert position == pytest.approx((0.3 - 2.0, 0.0, 2.0))
    assert velocity == (1.5, 0.0, 0.0)
    # a stale report is not flung further than the bound
    assert leader.predicted(20.0, max_lead_s=0.5).north == pytest.approx(0.75)


def test_route_times_its_legs_and_pauses() -> None:
    route = LeaderRoute([(0, 0, 8), (20, 0, 8), (20, 20, 8)], speed_ms=2.0, pause_s=2.0)
    assert route.duration_s == pytest.approx(2 + 10 + 2 + 10 + 2)
    assert route.leg_at(1.0) is None  # pausing at the start
    assert route.leg_at(3.0) == 0
    mid = route.state_at(7.0)
    assert (mid.north, mid.vn, mid.heading_rad) == pytest.approx((10.0, 2.0, 0.0))
    pause = route.state_at(13.0)  # at the corner, already facing the next leg
    assert (pause.north, pause.vn, pause.heading_rad) == pytest.approx((20.0, 0.0, math.pi / 2))


# -- the planner's refusals ---------------------------------------------------


def test_seed_formation_is_planned() -> None:
    plan = _plan(_request())
    assert set(plan.offsets) == {"f1", "f2"}
    assert plan.offsets["f1"].up == -6.0
    assert len(plan.route.legs) == 4


@pytest.mark.parametrize(
    ("overrides", "reason"),
    [
        ({"spacing_m": 1.0}, "minimum separation is 2 m"),
        (
            {"followers": [{"vehicle_id": "f1", "offset": {"x": -1.0, "y": 0.5}}]},
            "leader and f1 would be 1.12 m apart",
        ),
        ({"followers": [{"vehicle_id": "lead"}]}, "lead cannot lead and follow"),
        (
            {"followers": [{"vehicle_id": "f1"}, {"vehicle_id": "f1", "up": 3}]},
            "f1 is listed as a follower twice",
        ),
        ({"speed_ms": 12.0}, "12 m/s is above the vehicles' limit of 5 m/s"),
        ({"followers": [{"vehicle_id": "ghost"}]}, "ghost has not reported its state"),
        (
            {
                "controller": "consensus",
                "followers": [{"vehicle_id": "f1", "neighbours": ["f1"]}, {"vehicle_id": "f2"}],
            },
            "f1 cannot be its own neighbour",
        ),
        (
            {
                "controller": "consensus",
                "followers": [{"vehicle_id": "f1", "neighbours": ["lead"]}, {"vehicle_id": "f2"}],
            },
            "f1's neighbour lead is not a follower of this formation",
        ),
    ],
)
def test_bad_formations_are_refused_with_a_reason(overrides: dict[str, Any], reason: str) -> None:
    with pytest.raises(FormationRefused, match=reason):
        _plan(_request(**overrides))


def test_a_consensus_formation_hears_every_other_follower_unless_told() -> None:
    plan = _plan(_request(controller="consensus", k_neighbour=0.25))
    assert plan.controller is Controller.CONSENSUS
    assert plan.graph == {"f1": {"f2": 1.0}, "f2": {"f1": 1.0}}
    assert plan.gains == ConsensusGains(1.0, 0.25)
    one_way = _request(
        controller="consensus",
        followers=[{"vehicle_id": "f1", "neighbours": []}, {"vehicle_id": "f2"}],
    )
    assert _plan(one_way).graph == {"f1": {}, "f2": {"f1": 1.0}}
    assert _plan(_request()).graph == {}  # leader-following hears no neighbours


def test_busy_and_unready_vehicles_are_refused() -> None:
    with pytest.raises(FormationRefused, match="f2 is already in another formation"):
        _plan(_request(), busy={"f2"})
    with pytest.raises(FormationRefused, match="f1 is not ready to fly: GPS: no fix"):
        _plan(_request(), not_ready={"f1": "GPS: no fix"})


def test_mixed_frames_are_checked_at_every_heading() -> None:
    # 3 m behind in the heading frame and 3 m south: apart heading north, together south
    followers = [
        {"vehicle_id": "f1", "offset": {"x": -3.0, "y": 0.0}},
        {"vehicle_id": "f2", "offset": {"x": -3.0, "y": 0.0, "frame": "ne"}},
    ]
    with pytest.raises(FormationRefused, match=r"f1 and f2 would be 0\.00 m apart"):
        _plan(_request(followers=followers))


def test_route_is_checked_against_the_geofence_with_every_slot() -> None:
    # the fence holds the leader's square with 1 m to spare, not the slots 2 m outside it
    corners = [_geo(n, e) for n, e in [(-1, -1), (21, -1), (21, 21), (-1, 21)]]
    fence = Geofence(tuple(GeoPoint(lat, lon) for lat, lon in corners))
    _plan(_request(followers=[{"vehicle_id": "f1", "offset": {"x": 0, "y": 0, "up": -6}}],
                   min_separation_m=0.5), rails=SafetyRails(geofence=fence))  # fmt: skip
    with pytest.raises(FormationRefused, match="outside the geofence") as refused:
        _plan(_request(), rails=SafetyRails(geofence=fence))
    assert set(refused.value.violations) == {"f1", "f2"}  # the leader's own route is inside
