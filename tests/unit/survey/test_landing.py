"""How the survey judges a drone that stops flying, from the autopilot's reports alone:
landed with every lane flown is done; landed short, or disarmed on the ground before it
ever took off (PX4's preflight auto-disarm), drops out with the reason."""

from __future__ import annotations

from pathlib import Path

import pytest

from backend.errors import GcsError
from backend.survey.flight.run import DroneState, SurveyRun
from backend.survey.service import SurveyService
from protocol.messages import VehicleState, VehicleSummary
from tests.support.hubs import hub_settings
from tests.support.surveys import flying_run

LINK_TIMEOUT_S = 5.0


class _NoFleet:
    """The hub's registry as the hand-over offer reads it: no drone left to take lanes."""

    class registry:
        @staticmethod
        def get(vehicle_id: str) -> None:
            raise GcsError(f"no vehicle {vehicle_id}")


class _Clock:
    def __init__(self) -> None:
        self.now = 0.0

    def __call__(self) -> float:
        return self.now


def _service(tmp_path: Path, run: SurveyRun, clock: _Clock) -> SurveyService:
    settings = hub_settings(tmp_path, survey_link_timeout_s=LINK_TIMEOUT_S)
    service = SurveyService(_NoFleet(), None, None, settings, clock=clock)  # type: ignore[arg-type]
    service._runs[run.id] = run
    return service


def _report(service: SurveyService, vid: str, **state: object) -> None:
    service._on_state(
        VehicleSummary(
            id=vid,
            autopilot="px4",
            vehicle_type="quadrotor",
            modes=[],
            connected=True,
            state=VehicleState(**state),  # type: ignore[arg-type]
        )
    )


def test_a_drone_that_disarms_on_the_ground_drops_out_after_the_link_timeout(
    tmp_path: Path,
) -> None:
    run, clock = flying_run(1), _Clock()
    service = _service(tmp_path, run, clock)
    drone = run.drones[0]
    # The launch: not yet armed, then armed in MISSION, then disarmed by the autopilot
    # without leaving the ground.
    _report(service, drone.vehicle_id, armed=False, mode="MISSION", alt_rel=0.0)
    _report(service, drone.vehicle_id, armed=True, mode="MISSION", alt_rel=0.1)
    _report(service, drone.vehicle_id, armed=False, mode="MISSION", alt_rel=0.0)
    assert drone.state is DroneState.FLYING  # a replayed report may still be coming
    clock.now += LINK_TIMEOUT_S
    _report(service, drone.vehicle_id, armed=False, mode="MISSION", alt_rel=0.0)
    assert drone.state is DroneState.DROPPED
    assert drone.reason == "disarmed on the ground before it took off"


def test_one_never_airborne_is_not_done_though_its_mission_jumped_to_the_end(
    tmp_path: Path,
) -> None:
    run, clock = flying_run(1), _Clock()
    service = _service(tmp_path, run, clock)
    drone = run.drones[0]
    for lane in drone.lanes:
        lane.done = True  # PX4 jumped to the last item: every lane reads as flown
    _report(service, drone.vehicle_id, armed=True, mode="MISSION", alt_rel=0.0)
    _report(service, drone.vehicle_id, armed=False, mode="MISSION", alt_rel=0.0)
    clock.now += LINK_TIMEOUT_S
    _report(service, drone.vehicle_id, armed=False, mode="MISSION", alt_rel=0.0)
    assert drone.state is DroneState.DROPPED


@pytest.mark.parametrize("lanes_flown", [True, False], ids=["all-flown", "short"])
def test_a_drone_that_flew_and_landed_is_done_or_short(tmp_path: Path, lanes_flown: bool) -> None:
    run, clock = flying_run(1), _Clock()
    service = _service(tmp_path, run, clock)
    drone = run.drones[0]
    _report(service, drone.vehicle_id, armed=True, mode="MISSION", alt_rel=20.0)
    if lanes_flown:
        for lane in drone.lanes:
            lane.done = True
    _report(service, drone.vehicle_id, armed=False, mode="MISSION", alt_rel=0.0)
    if lanes_flown:
        assert drone.state is DroneState.DONE
        return
    clock.now += LINK_TIMEOUT_S
    _report(service, drone.vehicle_id, armed=False, mode="MISSION", alt_rel=0.0)
    assert drone.state is DroneState.DROPPED
    assert drone.reason == "landed before its lanes were flown"
