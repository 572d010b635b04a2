"""The formation follower's clock: the relayed stamps are Unix time, shared by the
fleet; their ages run on the agent's paced clock (the autopilot's seconds), never
slower than the wall's, so a stale leader state is never taken for a fresh one."""

from __future__ import annotations

from protocol.messages import EventKind, FormationSlot, LeaderUpdate, Neighbour
from tests.support.paced import FakeWall, paced_at
from vehicle_agents.control.executor import CommandExecutor
from vehicle_agents.control.formation_runner import FormationRunner
from vehicle_agents.control.formation_setpoint import Action
from vehicle_agents.fcu.link import FcuLink

UNIX = 1_800_000_000.0
OWN = (0.0, 0.0, 2.0)


def _runner(rate: float) -> tuple[FormationRunner, FakeWall, FakeWall]:
    """A follower joined to a formation, on an autopilot at ``rate``; its monotonic and
    Unix clocks, which the test moves together."""
    monotonic, unix = FakeWall(), FakeWall(UNIX)
    link = FcuLink("tcp:127.0.0.1:1")

    def emit(kind: EventKind, text: str, severity: int | None) -> None:
        pass

    runner = FormationRunner(
        link, CommandExecutor(link), emit, clock=paced_at(rate, monotonic), wall=unix
    )
    runner.on_hub(
        FormationSlot(
            formation_id="f1", origin_lat=0.0, origin_lon=0.0, x=-2, y=0, up=0, min_separation_m=2
        )
    )
    return runner, monotonic, unix


def _leader(sent_at: float, north: float = 10.0) -> LeaderUpdate:
    neighbour = Neighbour(vehicle_id="sim_3", north=0.0, east=5.0, up=2.0, time=sent_at)
    return LeaderUpdate(
        formation_id="f1",
        time=sent_at,
        north=north,
        east=0.0,
        up=2.0,
        vn=1.0,
        ve=0.0,
        vu=0.0,
        heading_deg=0.0,
        neighbours=[neighbour],
    )


def _action(runner: FormationRunner) -> Action:
    assert runner.follower is not None
    return runner.follower.tick(runner._clock(), OWN).action


def _wait(monotonic: FakeWall, unix: FakeWall, seconds: float) -> None:
    monotonic.now += seconds
    unix.now += seconds


def test_a_relayed_states_age_is_counted_in_the_autopilots_seconds() -> None:
    runner, monotonic, unix = _runner(4.0)
    runner.on_hub(_leader(UNIX - 0.1))  # 0.1 s on its way: 0.4 s of the simulator's
    follower = runner.follower
    assert follower is not None
    assert follower.leader is not None
    assert abs((runner._clock() - follower.leader.time_s) - 0.4) < 1e-6
    assert abs((runner._clock() - follower.neighbours["sim_3"].time_s) - 0.4) < 1e-6
    assert _action(runner) is Action.TRACK
    _wait(monotonic, unix, 0.1)  # 0.8 s old
    assert _action(runner) is Action.TRACK
    _wait(monotonic, unix, 0.1)  # 1.2 s old: over the 1 s rule
    assert _action(runner) is Action.HOLD_STALE


def test_a_stalled_autopilot_clock_still_ages_the_leader_in_wall_time() -> None:
    runner, monotonic, unix = _runner(0.0)
    runner.on_hub(_leader(UNIX - 0.1))
    _wait(monotonic, unix, 0.8)
    assert _action(runner) is Action.TRACK
    _wait(monotonic, unix, 0.2)  # 1.1 s since the leader was there, by the wall
    assert _action(runner) is Action.HOLD_STALE


def test_an_old_state_relayed_again_stays_old_and_an_overtaken_one_is_dropped() -> None:
    runner, monotonic, unix = _runner(4.0)
    runner.on_hub(_leader(UNIX))
    _wait(monotonic, unix, 0.3)  # the leader's agent went quiet; the hub relays its last
    runner.on_hub(_leader(UNIX))
    assert _action(runner) is Action.HOLD_STALE
    runner.on_hub(_leader(UNIX + 0.3, north=12.0))
    runner.on_hub(_leader(UNIX + 0.2, north=11.0))  # overtaken on the way
    assert runner.follower is not None
    assert runner.follower.leader is not None
    assert runner.follower.leader.north == 12.0
    assert _action(runner) is Action.TRACK


def test_a_stamp_ahead_of_this_agents_clock_counts_as_just_sent() -> None:
    runner, _, _ = _runner(4.0)
    runner.on_hub(_leader(UNIX + 5.0))  # the leader's computer's clock is ahead
    follower = runner.follower
    assert follower is not None
    assert follower.leader is not None
    assert follower.leader.time_s == runner._clock()
