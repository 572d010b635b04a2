"""The formation follower on the agent: its rules (feed-forward, a stale leader, an
intruder, its floor), the consensus law, the pilot's mode change, and the simulator's
answer to position-and-velocity targets as ArduCopter gives it."""

from __future__ import annotations

import math
from typing import Any

import pytest
from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from common.formation import (
    ConsensusGains,
    Controller,
    LeaderState,
    NeighbourState,
    Offset,
    consensus_target,
    slot_target,
)
from common.geodesy import LocalFrame
from simulator import DEFAULT_HOME
from simulator.mavconst import CopterMode
from tests.support.formation_sim import SimVehicle, take_off
from vehicle_agents.control.formation_follower import Follower, NeighbourReport
from vehicle_agents.control.formation_modes import ModeWatch
from vehicle_agents.control.formation_setpoint import POSVEL_TYPE_MASK, Action

HOME = LocalFrame(DEFAULT_HOME.lat, DEFAULT_HOME.lon)


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
