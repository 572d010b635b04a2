"""Formation missions: the shape presets, the planner's refusals, the follower's rules,
and the simulator's answer to position-and-velocity targets."""

from __future__ import annotations

import math
from typing import Any

import pytest
from pymavlink.dialects.v20 import ardupilotmega as mavlink2

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
    NeighbourState,
    Offset,
    OffsetFrame,
    Shape,
    consensus_target,
    shape_offsets,
    slot_target,
)
from common.geodesy import GeoPoint, LocalFrame
from simulator import DEFAULT_HOME
from simulator.mavconst import CopterMode
from tests.formation_sim import SimVehicle, take_off
from vehicle_agents.control.formation_follower import Follower, NeighbourReport
from vehicle_agents.control.formation_modes import ModeWatch
from vehicle_agents.control.formation_setpoint import POSVEL_TYPE_MASK, Action

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


# -- the follower's rules --------------------------------------------------------


def _follower(**kwargs: Any) -> Follower:
    return Follower(HOME, Offset(-2.0, 2.0, -6.0), min_separation_m=2.0, **kwargs)


def test_follower_tracks_with_velocity_feed_forward() -> None:
    follower = _follower()
    follower.on_leader(LeaderState(10.0, 0.0, 8.0, 1.5, 0.0, 0.0, 0.0, time_s=5.0))
    sp = follower.tick(5.1, own=(8.0, 2.0, 2.0))
    assert sp.action is Action.TRACK
    assert sp.position == pytest.approx((10.15 - 2.0, 2.0, 2.0))
    assert sp.velocity == (1.5, 0.0, 0.0)
    msg = follower.message(sp, 5100, 2, 1)
    assert msg is not None
    assert msg.type_mask == POSVEL_TYPE_MASK
    assert (msg.vx, msg.vy, msg.vz) == (1.5, 0.0, -0.0)
    assert msg.coordinate_frame == mavlink2.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT
    # ArduCopter's set_destination_posvelaccel: no bit of position or velocity set
    assert not msg.type_mask & 0b111111


def test_follower_holds_when_the_leader_goes_stale() -> None:
    follower = _follower()
    assert follower.tick(0.0, own=(0.0, 0.0, 2.0)).action is Action.HOLD_STALE  # none yet
    follower.on_leader(LeaderState(10.0, 0.0, 8.0, 1.5, 0.0, 0.0, 0.0, time_s=5.0))
    assert follower.tick(5.9, own=(8.0, 2.0, 2.0)).action is Action.TRACK
    stale = follower.tick(6.1, own=(8.2, 2.0, 2.0))
    assert stale.action is Action.HOLD_STALE
    assert "1.1 s old" in stale.reason
    assert stale.position == (8.2, 2.0, 2.0)
    assert stale.velocity == (0.0, 0.0, 0.0)
    # the hold stays where it began, not where the vehicle drifts
    assert follower.tick(6.5, own=(8.5, 2.0, 2.0)).position == (8.2, 2.0, 2.0)
    # an older report arriving late does not replace a newer one
    follower.on_leader(LeaderState(0.0, 0.0, 8.0, 0.0, 0.0, 0.0, 0.0, time_s=4.0))
    assert follower.leader is not None
    assert follower.leader.time_s == 5.0


def test_follower_backs_off_from_an_intruder_then_leaves_on_request() -> None:
    follower = _follower()
    follower.on_leader(LeaderState(10.0, 0.0, 8.0, 1.5, 0.0, 0.0, 0.0, time_s=5.0))
    sp = follower.tick(5.0, own=(8.0, 2.0, 2.0), others={"intruder": (8.0, 3.0, 2.0)})
    assert sp.action is Action.BACK_OFF
    assert "intruder is 1.0 m away" in sp.reason
    assert sp.velocity == pytest.approx((0.0, -1.0, 0.0))  # straight away from it
    follower.leave("RC mode change to LOITER")
    gone = follower.tick(5.1, own=(8.0, 2.0, 2.0))
    assert gone.action is Action.LEFT
    assert follower.message(gone, 0, 2, 1) is None


def test_follower_never_targets_below_its_floor() -> None:
    follower = _follower()
    follower.on_leader(LeaderState(0.0, 0.0, 3.0, 0.0, 0.0, -1.0, 0.0, time_s=0.0))
    sp = follower.tick(0.0, own=(0.0, 0.0, 2.0))
    assert sp.position is not None
    assert sp.position[2] == 1.0
    assert sp.velocity[2] == 0.0


# -- consensus ----------------------------------------------------------------------

LEADER_EAST = LeaderState(0.0, 0.0, 8.0, 0.0, 1.5, 0.0, math.pi / 2, time_s=0.0)
RIGHT_SLOT, LEFT_SLOT = Offset(-2.0, 2.0, -6.0), Offset(-2.0, -2.0, -5.0)


def test_consensus_without_neighbours_is_the_leaders_slot() -> None:
    target, velocity = consensus_target(LEADER_EAST, RIGHT_SLOT, [], ConsensusGains())
    assert target == pytest.approx(slot_target(LEADER_EAST, RIGHT_SLOT)[0])
    assert velocity == (0.0, 1.5, 0.0)  # the leader's, as feed-forward


def test_consensus_flies_the_law_through_the_autopilots_position_loop() -> None:
    """A neighbour lagging 1.5 m behind its slot pulls the target back by its weight's
    share; the autopilot's v = v_ff + K (target - p) is then the law with k_L + k_n = K."""
    slot, _ = slot_target(LEADER_EAST, LEFT_SLOT)
    lagging = NeighbourState((slot[0], slot[1] - 1.5, slot[2]), LEFT_SLOT, weight=1.0)
    gains = ConsensusGains(k_leader=1.0, k_neighbour=0.5)
    target, v_ff = consensus_target(LEADER_EAST, RIGHT_SLOT, [lagging], gains)
    own_slot, _ = slot_target(LEADER_EAST, RIGHT_SLOT)
    assert target == pytest.approx((own_slot[0], own_slot[1] - 0.5, own_slot[2]))
    # the law, from a follower 0.3 m north of its slot, with K = 1 and gains scaled to it
    p_i = (own_slot[0] + 0.3, own_slot[1], own_slot[2])
    k_l, k_n = 1.0 / 1.5, 0.5 / 1.5
    d_i = RIGHT_SLOT.north_east_up(LEADER_EAST.heading_rad)
    d_j = LEFT_SLOT.north_east_up(LEADER_EAST.heading_rad)
    leader_p = (LEADER_EAST.north, LEADER_EAST.east, LEADER_EAST.up)
    law = [
        v_ff[a]
        + k_l * (leader_p[a] + d_i[a] - p_i[a])
        + k_n * ((lagging.position[a] - d_j[a]) - (p_i[a] - d_i[a]))
        for a in range(3)
    ]
    autopilot = [v_ff[a] + 1.0 * (target[a] - p_i[a]) for a in range(3)]
    assert autopilot == pytest.approx(law)


def test_a_consensus_follower_drops_a_stale_neighbour() -> None:
    follower = Follower(
        HOME, RIGHT_SLOT, 2.0, controller=Controller.CONSENSUS, gains=ConsensusGains(1.0, 1.0)
    )
    follower.graph = {"f2": (LEFT_SLOT, 1.0)}
    follower.on_leader(LEADER_EAST)
    slot, _ = slot_target(LEADER_EAST, LEFT_SLOT)
    behind = (slot[0], slot[1] - 2.0, slot[2])
    follower.neighbours = {"f2": NeighbourReport(behind, (0.0, 1.5, 0.0), time_s=0.0)}
    own_slot, _ = slot_target(LEADER_EAST, RIGHT_SLOT)
    fresh = follower.tick(0.0, own=own_slot)
    assert fresh.action is Action.TRACK
    assert fresh.position == pytest.approx((own_slot[0], own_slot[1] - 1.0, own_slot[2]))
    assert fresh.velocity == (0.0, 1.5, 0.0)
    # the neighbour's report ages past 1 s while the leader's stays fresh: the leader's
    # pull alone (at 1.5 m/s the slot has moved on 1.2 m by then)
    follower.on_leader(LeaderState(0.0, 1.2, 8.0, 0.0, 1.5, 0.0, math.pi / 2, time_s=1.2))
    alone = follower.tick(1.2, own=own_slot)
    assert alone.position == pytest.approx(slot_target(follower.leader, RIGHT_SLOT)[0])


def test_a_mode_change_before_the_agents_switch_is_the_pilots() -> None:
    """A second formation on followers already in their slots: the pilot switches to
    LOITER within the pre-stream, before any guided heartbeat. That is a leave, and the
    agent must not switch the vehicle back to GUIDED (it used to)."""
    watch = ModeWatch("GUIDED", "GUIDED")  # the operator put it in GUIDED before starting
    assert watch.observe("LOITER") is not None
    assert not watch.needs_switch("LOITER")
    braked = ModeWatch("GUIDED", "BRAKE")  # held after the first formation
    assert braked.needs_switch("BRAKE")  # the agent's own switch, after its pre-stream
    assert braked.observe("BRAKE") is None
    left = braked.observe("LOITER")  # the pilot's, from BRAKE, before the agent's
    assert "changed to LOITER" in (left or "")


def test_the_agents_own_switch_to_guided_is_not_a_leave() -> None:
    watch = ModeWatch("GUIDED", None)  # no heartbeat yet at the join
    assert watch.observe("BRAKE") is None  # the first one gives the join's mode
    assert watch.needs_switch("BRAKE")
    assert watch.observe("GUIDED") is None
    assert not watch.needs_switch("GUIDED")
    assert "changed to RTL" in (watch.observe("RTL") or "")


# -- the simulator answers velocity targets as ArduCopter does ------------------


def _posvel(vehicle: SimVehicle, north: float, vn: float, mask: int) -> None:
    lat, lon = vehicle.copter.frame.to_geo(0.0, north)
    vehicle.send(
        mavlink2.MAVLink_set_position_target_global_int_message(
            0,
            vehicle.system_id,
            1,
            mavlink2.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT,
            mask,
            round(lat * 1e7),
            round(lon * 1e7),
            10.0,
            vn,
            0.0,
            0.0,
            0,
            0,
            0,
            0,
            0,
        )
    )


def test_simulator_flies_velocity_feed_forward_and_stops_on_guid_timeout() -> None:
    vehicle = SimVehicle(DEFAULT_HOME, 1)
    take_off(vehicle, 10.0)
    vehicle.copter.advance(15.0)
    body = vehicle.copter.body
    # position and velocity: the target moves on at 2 m/s between messages
    _posvel(vehicle, 0.0, 2.0, POSVEL_TYPE_MASK)
    vehicle.copter.advance(2.5)
    assert vehicle.copter.guided_target is not None
    assert vehicle.copter.guided_target[0] == pytest.approx(5.0, abs=0.05)
    _posvel(vehicle, 5.0, 2.0, POSVEL_TYPE_MASK)
    vehicle.copter.advance(2.5)
    # on its moving target at its velocity: no trailing lag
    assert body.vn == pytest.approx(2.0, abs=0.05)
    assert body.north == pytest.approx(10.0, abs=0.1)
    # no fresh target for GUID_TIMEOUT (3 s): the velocity is dropped and it stops
    vehicle.copter.advance(8.0)
    assert abs(body.vn) < 0.05
    # on the target as it stood when the velocity ran out: 5 m + 2 m/s for 3 s
    assert body.north == pytest.approx(11.0, abs=0.1)
    stopped = body.north
    vehicle.copter.advance(2.0)
    assert body.north == pytest.approx(stopped, abs=0.05)
    # any velocity bit set ignores the velocity (ArduCopter's group test): position only
    _posvel(vehicle, stopped, 2.0, POSVEL_TYPE_MASK | mavlink2.POSITION_TARGET_TYPEMASK_VX_IGNORE)
    vehicle.copter.advance(3.0)
    assert body.north == pytest.approx(stopped, abs=0.05)
    # velocity only: from where it is, at that velocity
    _posvel(vehicle, 0.0, -1.0, POSVEL_TYPE_MASK | 0b111)
    vehicle.copter.advance(2.0)
    assert body.vn == pytest.approx(-1.0, abs=0.05)
    assert vehicle.copter.mode is CopterMode.GUIDED
