"""A survey in flight, without the hub: progress from the autopilots' reports, and the
hand-over of a lost drone's unflown lanes to the drones still flying."""

from __future__ import annotations

import math

import pytest
from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from backend.survey.flight.handover import (
    Flyer,
    accept_offer,
    flyer_of,
    handover_missions,
    split_orphans,
)
from backend.survey.flight.run import DroneState, SurveyRun, SurveyState, covered_fraction, geometry
from backend.survey.planning.camera import CameraCalc, calculate, preset
from backend.survey.planning.mission import survey_mission
from backend.survey.planning.planner import plan_lanes
from common.geodesy import GeoPoint
from protocol.messages import Photo
from tests.support.surveys import LAT, LON, flying_run


def test_lane_items_point_at_the_lanes_entry_and_exit_waypoints() -> None:
    run = flying_run(1)
    geo = geometry(run)
    plan = plan_lanes(geo.area, _calc(run), angle_deg=0)
    mission = survey_mission(
        plan, geo.frame, 40.0, takeoff=GeoPoint(*geo.frame.to_geo(-20.0, -30.0)), speed_ms=10.0
    )
    for lane, (entry, exit_) in zip(plan.lanes, mission.lanes, strict=True):
        first, last = mission.items[entry - 1], mission.items[exit_ - 1]
        assert first.command == last.command == mavlink2.MAV_CMD_NAV_WAYPOINT
        assert math.dist(geo.frame.to_local(first.lat, first.lon), lane.start) < 0.01
        assert math.dist(geo.frame.to_local(last.lat, last.lon), lane.end) < 0.01
        # the camera starts after the entry and stops after the exit
        assert mission.items[entry].command == mavlink2.MAV_CMD_DO_SET_CAM_TRIGG_DIST
        assert mission.items[exit_].param1 == 0
    # DO_CHANGE_SPEED right after the take-off, to the survey's speed
    assert mission.items[1].command == mavlink2.MAV_CMD_DO_CHANGE_SPEED
    assert mission.items[1].param2 == pytest.approx(10.0)


def _calc(run: SurveyRun) -> CameraCalc:
    return calculate(preset("sony_a6000_16mm"), altitude_m=run.altitude_m)


def test_progress_comes_from_reached_items_current_item_and_photos() -> None:
    run = flying_run(2)
    first = run.drones[0]
    total = run.lanes_total()
    assert run.lanes_done() == 0
    assert run.reached("d0", first.lanes[0].exit)
    assert first.lanes[0].done
    assert not first.lanes[1].done
    # MISSION_CURRENT past a lane's exit: flown, even if its MISSION_ITEM_REACHED was lost
    assert run.current_item("d0", first.lanes[1].exit + 1)
    assert first.lanes[1].done
    assert run.lanes_done() == 2
    assert run.lanes_total() == total
    photo = Photo(index=1, lat=LAT, lon=LON, alt_rel=40)
    assert run.photo("d0", photo)
    assert not run.photo("d0", photo)  # delivered twice, counted once
    # the same number elsewhere is another photo (a second camera, a restarted counter)
    assert run.photo("d0", Photo(index=1, lat=LAT + 0.0002, lon=LON, alt_rel=40))
    assert not run.photo("d0", Photo(index=1, lat=LAT + 0.0002, lon=LON, alt_rel=40))
    # replayed late, after the drone was seen landed: counted if taken before that
    first.finished = 2_000.0
    assert run.photo("d0", Photo(index=2, lat=LAT, lon=LON, alt_rel=40), 1_990.0)
    assert not run.photo("d0", Photo(index=3, lat=LAT, lon=LON, alt_rel=40), 2_500.0)
    assert run.photo_count() == 3
    assert 0 < covered_fraction(run, geometry(run)) < 1


def test_split_orphans_gives_every_lost_lane_to_exactly_one_drone_balanced() -> None:
    orphans = [((0.0, 20.0 * i), (300.0, 20.0 * i)) for i in range(10)]
    flyers = [
        Flyer("a", (0.0, -50.0), (0.0, -60.0), [], False),
        Flyer("b", (300.0, -50.0), (300.0, -60.0), [((0.0, -40.0), (300.0, -40.0))], True),
    ]
    shares = split_orphans(orphans, flyers, 10.0, 10.0)
    taken = [lane for vid in shares for lane in shares[vid]]
    own = ((0.0, -40.0), (300.0, -40.0))
    assert shares["b"][0] == own  # its own lane first
    moved = [tuple(sorted(lane)) for lane in taken if lane != own]
    assert sorted(moved) == sorted(tuple(sorted(lane)) for lane in orphans)
    # b has a lane of its own already: a takes more of the lost ones
    assert len(shares["a"]) > len(shares["b"]) - 1


def test_a_lost_drone_s_unflown_lanes_go_to_the_others_resuming_where_they_are() -> None:
    run = flying_run(3)
    keeper, lost, other = run.drones
    run.reached("d1", lost.lanes[0].exit)  # d1 flew one lane, then its link went
    lost.state = DroneState.DROPPED
    # d0 is part way along its second lane: flying to its exit
    run.reached("d0", keeper.lanes[0].exit)
    run.current_item("d0", keeper.lanes[1].exit)
    geo = geometry(run)
    where = {
        "d0": geo.frame.to_local(*keeper.lanes[1].start),
        "d2": geo.frame.to_local(*other.lanes[0].start),
    }
    where["d0"] = (where["d0"][0] + 30.0, where["d0"][1])
    flyers = [flyer_of(d, geo, where[d.vehicle_id], (0.0, -30.0)) for d in (keeper, other)]
    assert flyers[0].mid_lane
    assert flyers[0].lanes[0][0] == where["d0"]
    offer = handover_missions(run, geo, flyers, "d1 link lost")
    assert offer.lost == ["d1"]
    assert offer.lanes_moved == len(lost.lanes) - 1
    for vid, items in offer.missions.items():
        commands = [item.command for item in items]
        assert mavlink2.MAV_CMD_NAV_TAKEOFF not in commands
        assert commands[-1] == mavlink2.MAV_CMD_NAV_RETURN_TO_LAUNCH
        first = next(i for i in items if i.command == mavlink2.MAV_CMD_NAV_WAYPOINT)
        if vid == "d0":
            # mid-lane: resumes where it is, camera on at once
            assert math.dist(geo.frame.to_local(first.lat, first.lon), where["d0"]) < 0.01
    total = run.lanes_total()
    run.offer = offer
    run.state = SurveyState.HANDOVER_OFFERED
    accept_offer(run)
    assert run.state is SurveyState.FLYING
    assert run.handovers == 1
    # The part-flown lane of d0 is counted once: its rest is in the new mission.
    assert run.lanes_total() == total
    assert lost.lanes == []
    assert lost.lanes_done_before == 1
    assert not run.orphans()
