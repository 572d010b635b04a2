"""The hub flies a simulated fleet's formation in the vehicles' seconds (GCS_FLEET_SPEEDUP,
development only): the route, and the leader's age, which is never less than the wall's."""

from __future__ import annotations

from typing import Any, cast

import pytest
from pydantic import ValidationError

from backend.fleet.registry import FleetRegistry, VehicleRecord
from backend.formation.active import ActiveFormation
from backend.formation.planner import FormationPlan
from backend.formation.route import LeaderRoute
from backend.formation.schemas import FormationRequest
from backend.formation.service import FormationService
from backend.settings import HubSettings
from common.geodesy import LocalFrame
from protocol.messages import VehicleState

HOME = LocalFrame(47.0, 8.0)
FORMED_AT = 1_800_000_000.0


def _formation(leader_id: str | None) -> ActiveFormation:
    route = LeaderRoute([(0, 0, 8), (20, 0, 8)], speed_ms=2.0, pause_s=2.0)
    plan = FormationPlan(leader_id, HOME, route, {}, 2.0)
    request = cast(FormationRequest, None)  # not read by the relay
    return ActiveFormation("f1", request, plan, FORMED_AT, formed_at=FORMED_AT)


def _service(speedup: float, registry: FleetRegistry | None = None) -> FormationService:
    return FormationService(registry or FleetRegistry(), cast(Any, None), speedup=speedup)


def test_a_virtual_leader_flies_its_route_in_the_vehicles_seconds() -> None:
    formation = _formation(None)
    leader = _service(4.0).leader_state(formation, FORMED_AT + 1.75)
    expected = formation.plan.route.state_at(7.0)  # 1.75 s of the wall's at 4x
    assert leader is not None
    assert (leader.north, leader.vn) == pytest.approx((expected.north, expected.vn))
    assert leader.time_s == FORMED_AT + 1.75  # stamps stay Unix time


def test_a_leader_reports_age_is_counted_in_the_vehicles_seconds() -> None:
    registry = FleetRegistry()
    lat, lon = HOME.to_geo(0.0, 0.0)
    registry._vehicles["lead"] = VehicleRecord(
        "lead",
        "ardupilot",
        "copter",
        [],
        last_seen=FORMED_AT,
        state=VehicleState(lat=lat, lon=lon, alt_rel=8.0),
    )
    formation = _formation("lead")
    assert _service(1.0, registry).leader_state(formation, FORMED_AT + 0.3) is not None
    # 0.3 s of the wall's is 1.2 s of a 4x fleet's: too old to relay
    assert _service(4.0, registry).leader_state(formation, FORMED_AT + 0.3) is None


def test_a_fleet_speedup_is_for_simulated_fleets_in_development_only() -> None:
    with pytest.raises(ValidationError, match="GCS_FLEET_SPEEDUP is for simulated fleets"):
        HubSettings(admin_password="an admin password nobody guesses 7", fleet_speedup=4.0)
    assert HubSettings(environment="development", fleet_speedup=4.0).fleet_speedup == 4.0
    with pytest.raises(ValidationError):
        HubSettings(environment="development", fleet_speedup=0.5)  # never slower than wall


def test_a_formation_says_when_its_route_is_done_in_the_fleets_seconds() -> None:
    """The route (10 s of flight, 2 s of pause at each end: 14 s) at 4x ends 3.5 s of the
    wall's after it formed; the state says so, with no sum for a client to do."""
    formation = _formation(None)
    formation.speedup = 4.0
    assert formation.plan.route.duration_s == pytest.approx(14.0)
    assert formation.route_done_at == pytest.approx(FORMED_AT + 3.5)
    assert formation.state(FORMED_AT + 3.0) == "flying"
    assert formation.state(FORMED_AT + 3.5) == "route_done"
    joining = _formation(None)
    joining.formed_at = None
    assert (joining.state(FORMED_AT), joining.route_done_at) == ("joining", None)
    # stopped before the end: the route was never done
    formation.stopped, formation.stopped_at = "stopped by the operator", FORMED_AT + 1.0
    assert (formation.state(FORMED_AT + 9.0), formation.route_done_at) == ("stopped", None)
