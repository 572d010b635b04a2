"""The seed experiment in the sped-up simulator: a leader flies a 20 m square at 1.5 m/s
at 8 m, pausing 2 s at each corner, and two followers hold a triangle at 2 m and 3 m.
The seed's open-loop waypoints trailed by about 2.5 m; the design's bar is 0.5 m RMS."""

from __future__ import annotations

import math

from common.formation import ConsensusGains, Controller
from common.geodesy import LocalFrame
from simulator import DEFAULT_HOME
from tests.support.formation_sim import SimVehicle, fly_formation
from vehicle_agents.control.formation_follower import Follower
from vehicle_agents.control.formation_setpoint import Action

MIN_SEPARATION_M = 2.0


def test_seed_square_is_tracked_within_half_a_metre_rms() -> None:
    run = fly_formation(min_separation_m=MIN_SEPARATION_M)
    for follower in run.errors_xy:
        assert run.rms_xy(follower) <= 0.5, (follower, run.rms_xy(follower))
        assert max(run.errors_z[follower]) < 0.5
    assert run.min_separation_m >= MIN_SEPARATION_M
    # nobody had to back off or hold: the leader's state was fresh throughout
    assert {a for actions in run.actions.values() for a in actions} == {"track"}


def test_seed_square_with_the_consensus_controller() -> None:
    """The same flight with consensus (k_leader 1, k_neighbour 0.5, each follower hearing
    the other). Bound: 0.5 m RMS, the design's bar, and within 0.15 m of leader-following.
    Why: the target is 2/3 the leader's slot and 1/3 where the other follower puts it; on
    a steady leg both agree with the leader, so the legs' error is the corners' again,
    plus a third of the partner's corner transient (the slots swing 4.2 m apart at each
    90-degree turn): measured 0.33 m, against 0.26 m for leader-following
    (the law itself is checked in tests/unit/formation/test_follower.py)."""
    consensus = fly_formation(
        min_separation_m=MIN_SEPARATION_M,
        controller=Controller.CONSENSUS,
        gains=ConsensusGains(k_leader=1.0, k_neighbour=0.5),
    )
    for follower in consensus.errors_xy:
        assert consensus.rms_xy(follower) <= 0.5, (follower, consensus.rms_xy(follower))
        assert max(consensus.errors_z[follower]) < 0.5
    assert consensus.min_separation_m >= MIN_SEPARATION_M
    assert {a for actions in consensus.actions.values() for a in actions} == {"track"}


def test_without_feed_forward_the_followers_trail() -> None:
    """The same flight with position-only targets: the seed's lag (speed over the
    position gain) comes back, which is what the feed-forward removes."""
    run = fly_formation(min_separation_m=MIN_SEPARATION_M, feed_forward=False)
    assert run.worst_rms_xy > 1.0


def test_followers_hold_when_the_leader_goes_stale() -> None:
    """The leader's reports stop 10 s into the route (mid-leg, at 1.5 m/s): within the
    1 s rule the followers hold and come to rest, while the leader flies on."""
    seen: dict[str, float] = {}

    def watch(t: float, vehicles: list[SimVehicle], followers: list[Follower]) -> None:
        route_t = t - 25.0
        if 12.5 <= route_t < 13.0:  # 2.5 s after the cut
            seen["follower_speed"] = max(v.copter.body.groundspeed for v in vehicles[1:])
            seen["leader_speed"] = vehicles[0].copter.body.groundspeed

    run = fly_formation(leader_cut_at_s=10.0, route_laps=0.4, on_tick=watch)
    for actions in run.actions.values():
        first_hold = actions.index(Action.HOLD_STALE)
        # the last report came at most one 0.1 s tick before the cut: held 1 s after it
        assert 10.9 < run.action_times[first_hold] <= 11.2
        assert set(actions[first_hold:]) == {Action.HOLD_STALE}
    assert seen["follower_speed"] < 0.2
    assert seen["leader_speed"] > 1.0


def test_a_follower_backs_off_from_a_vehicle_inside_the_separation() -> None:
    """Mid-leg the separation rises above the followers' distance from each other (about
    4.4 m): each is now inside the other's, and both back off until they are clear."""
    frame = LocalFrame(DEFAULT_HOME.lat, DEFAULT_HOME.lon)
    gaps: list[float] = []

    def widen(t: float, vehicles: list[SimVehicle], followers: list[Follower]) -> None:
        if t - 25.0 >= 6.0:
            for follower in followers:
                follower.min_separation_m = 5.0
            a, b = (v.local(frame) for v in vehicles[1:])
            gaps.append(math.dist(a, b))

    run = fly_formation(route_laps=0.35, on_tick=widen, min_separation_m=2.0)
    assert gaps[0] < 5.0
    for actions in run.actions.values():
        assert Action.BACK_OFF in actions
        assert Action.HOLD_CLEAR in actions  # then hold clear rather than re-enter
    # clear within 3 s, and kept clear (they hold at the edge, not back into the slot)
    assert min(gaps[30:]) > 4.9, min(gaps[30:])
