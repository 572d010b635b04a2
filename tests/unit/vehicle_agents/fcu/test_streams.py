"""The agent's stream plan: defaults, overrides, and the REQUEST_DATA_STREAM fallback."""

from __future__ import annotations

import itertools

import pytest
from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from vehicle_agents.fcu.rate_merger import ALL_GROUPS, IntervalAnswer, RateMerger
from vehicle_agents.fcu.stream_plan import (
    DATA_STREAM_GROUPS,
    DEFAULT_RATES_HZ,
    StreamRequest,
    data_stream_rates,
    message_id,
    stream_plan,
)
from vehicle_agents.fcu.stream_watch import RateWatch, RateWatchSettings


def rates(plan: list[StreamRequest]) -> dict[str, float]:
    return {request.message: request.rate_hz for request in plan}


def test_the_defaults_cover_what_the_snapshot_reads() -> None:
    plan = stream_plan({})
    assert rates(plan) == dict(DEFAULT_RATES_HZ)
    assert {"GLOBAL_POSITION_INT", "GPS_RAW_INT", "GPS2_RAW", "HOME_POSITION"} <= set(rates(plan))
    assert plan[0].message == "GLOBAL_POSITION_INT"  # the probe: every autopilot has it
    by_name = {request.message: request for request in plan}
    assert by_name["GPS2_RAW"].msg_id == 124
    assert by_name["GLOBAL_POSITION_INT"].interval_us == 100_000
    assert by_name["HOME_POSITION"].interval_us == 5_000_000


def test_overrides_merge_over_the_defaults() -> None:
    plan = stream_plan({"attitude": 25, "RC_CHANNELS": 2, "GPS2_RAW": 0})
    merged = rates(plan)
    assert merged["ATTITUDE"] == 25.0
    assert merged["RC_CHANNELS"] == 2.0  # extra messages are added
    assert merged["GLOBAL_POSITION_INT"] == DEFAULT_RATES_HZ["GLOBAL_POSITION_INT"]
    by_name = {request.message: request for request in plan}
    assert by_name["GPS2_RAW"].interval_us == -1  # 0 Hz: stop it
    assert by_name["ATTITUDE"].interval_us == 40_000
    assert len(plan) == len(DEFAULT_RATES_HZ) + 1


@pytest.mark.parametrize(
    ("overrides", "error"),
    [
        ({"NOT_A_MESSAGE": 1.0}, "unknown MAVLink message 'NOT_A_MESSAGE'"),
        ({"ATTITUDE": -1.0}, "ATTITUDE must be >= 0 Hz"),
        ({"ATTITUDE": float("nan")}, "ATTITUDE must be >= 0 Hz"),
    ],
)
def test_bad_rates_are_refused_before_connecting(overrides: dict[str, float], error: str) -> None:
    with pytest.raises(ValueError, match=error):
        stream_plan(overrides)


def test_message_ids_come_from_the_dialect() -> None:
    assert message_id("HEARTBEAT") == 0
    assert message_id("EXTENDED_SYS_STATE") == 245
    with pytest.raises(ValueError, match="unknown"):
        message_id("MAV_CMD_NAV_LAND")


def test_the_fallback_asks_each_group_at_its_fastest_member() -> None:
    plan = stream_plan({"GPS_RAW_INT": 5, "GPS2_RAW": 0.5, "SYS_STATUS": 1.5})
    groups = data_stream_rates(plan)
    assert groups == {
        mavlink2.MAV_DATA_STREAM_POSITION: 10,
        mavlink2.MAV_DATA_STREAM_EXTRA1: 10,
        mavlink2.MAV_DATA_STREAM_EXTRA2: 4,
        mavlink2.MAV_DATA_STREAM_EXTENDED_STATUS: 5,
        mavlink2.MAV_DATA_STREAM_EXTRA3: 1,  # BATTERY_STATUS
    }
    # fractional rates round up: the group is never slower than asked
    assert data_stream_rates(stream_plan({"ATTITUDE": 0.2}))[mavlink2.MAV_DATA_STREAM_EXTRA1] == 1


def test_a_group_whose_messages_are_all_stopped_is_stopped() -> None:
    plan = stream_plan({"ATTITUDE": 0, "VFR_HUD": 0})
    groups = data_stream_rates(plan)
    assert groups[mavlink2.MAV_DATA_STREAM_EXTRA1] == 0
    assert groups[mavlink2.MAV_DATA_STREAM_EXTRA2] == 0


def test_groups_name_real_messages() -> None:
    for names in DATA_STREAM_GROUPS.values():
        for name in names:
            message_id(name)
    grouped = {name for names in DATA_STREAM_GROUPS.values() for name in names}
    assert set(DEFAULT_RATES_HZ) - grouped == {"HOME_POSITION", "EXTENDED_SYS_STATE"}


# -- the achieved rates, on an injected clock ---------------------------------------------


class Clock:
    def __init__(self) -> None:
        self.now = 100.0

    def __call__(self) -> float:
        return self.now


def arrive(watch: RateWatch, clock: Clock, rate_hz: float, seconds: float) -> None:
    """GLOBAL_POSITION_INT at ``rate_hz`` for ``seconds``, the clock moving with it."""
    message = mavlink2.MAVLink_global_position_int_message(0, 1, 1, 0, 0, 0, 0, 0, 0)
    for _ in range(round(rate_hz * seconds)):
        clock.now += 1 / rate_hz
        watch.on_message(message)


def test_a_message_slowed_by_another_gcs_is_asked_for_again_with_backoff() -> None:
    clock = Clock()
    watch = RateWatch(RateWatchSettings(window_s=2.0, retry_max_s=8.0), clock)
    plan = stream_plan({})
    watch.watch(plan)
    arrive(watch, clock, 10, 3)
    assert watch.due() == []  # at the rate asked for
    assert watch.achieved_hz("GLOBAL_POSITION_INT") == pytest.approx(10, abs=0.5)
    arrive(watch, clock, 4, 2)  # another GCS set 4 Hz
    [again] = watch.due()
    assert (again.message, again.rate_hz) == ("GLOBAL_POSITION_INT", 10.0)
    assert watch.due() == []  # not again before the next window
    # still slow: asked again after 2 s, then 4 s, then 8 s (the cap), then 8 s
    asked_at = [clock.now]
    for _ in range(60):
        arrive(watch, clock, 4, 0.5)
        if watch.due():
            asked_at.append(clock.now)
    gaps = [round(b - a) for a, b in itertools.pairwise(asked_at)]
    assert gaps == [2, 4, 8, 8, 8], asked_at
    assert watch.rerequests == len(asked_at)
    arrive(watch, clock, 10, 10)  # restored
    assert watch.due() == []


def test_messages_not_yet_seen_or_stopped_are_not_judged() -> None:
    clock = Clock()
    watch = RateWatch(RateWatchSettings(window_s=1.0), clock)
    watch.watch(stream_plan({"ATTITUDE": 0}))
    arrive(watch, clock, 10, 5)  # only GLOBAL_POSITION_INT comes: no GPS2_RAW on board
    assert watch.due() == []
    assert watch.achieved_hz("ATTITUDE") is None  # stopped: nothing to hold it to
    # a slow message is measured over enough of its own periods
    watch.watch(stream_plan({"GLOBAL_POSITION_INT": 0.2}))
    arrive(watch, clock, 0.2, 20)
    assert watch.due() == []


# -- the rates of everyone on the link, merged -------------------------------------------

MAVPROXY = (250, 230)
QGC = (255, 190)
GPI = mavlink2.MAVLINK_MSG_ID_GLOBAL_POSITION_INT


def _merger() -> RateMerger:
    merger = RateMerger()
    merger.set_agent(stream_plan({}))
    return merger


def test_a_gcs_data_stream_request_is_merged_with_the_agents_needs_and_sent_once() -> None:
    merger = _merger()
    changed = merger.data_stream(MAVPROXY, mavlink2.MAV_DATA_STREAM_ALL, 4, True)
    # ArduPilot's ALL sets every group: none below what the agent needs of it.
    assert changed[mavlink2.MAV_DATA_STREAM_POSITION] == 10
    assert changed[mavlink2.MAV_DATA_STREAM_EXTRA1] == 10
    assert changed[mavlink2.MAV_DATA_STREAM_EXTRA2] == 4
    assert changed[mavlink2.MAV_DATA_STREAM_RAW_SENSORS] == 4
    assert len(changed) == len(ALL_GROUPS)
    # MAVProxy asks again every ~15 s: nothing new, nothing sent.
    assert merger.data_stream(MAVPROXY, mavlink2.MAV_DATA_STREAM_ALL, 4, True) == {}
    assert merger.absorbed == 1
    # A second GCS wants more of one group, then stops it: the group follows the highest.
    extra3 = mavlink2.MAV_DATA_STREAM_EXTRA3
    assert merger.data_stream(QGC, extra3, 8, True) == {extra3: 8}
    assert merger.data_stream(QGC, extra3, 0, False) == {extra3: 4}
    # MAVProxy stops everything: the agent's own needs stay.
    stopped = merger.data_stream(MAVPROXY, mavlink2.MAV_DATA_STREAM_ALL, 4, False)
    assert mavlink2.MAV_DATA_STREAM_POSITION not in stopped  # 10 Hz, as it was
    assert stopped[extra3] == 1  # BATTERY_STATUS, EKF_STATUS_REPORT at 1 Hz
    assert stopped[mavlink2.MAV_DATA_STREAM_RAW_SENSORS] == 0  # nobody's: stopped


def test_a_gcs_message_interval_is_answered_sent_on_or_merged() -> None:
    merger = _merger()
    merger.note_interval(GPI, 10.0)  # the agent's own, accepted
    # Lower than the agent's: answered here, nothing sent.
    assert merger.message_interval(MAVPROXY, GPI, 250_000) == IntervalAnswer(forward=False)
    # Higher: the GCS's own request goes on (the autopilot answers it), once.
    assert merger.message_interval(MAVPROXY, GPI, 50_000) == IntervalAnswer(forward=True)
    assert merger.message_interval(MAVPROXY, GPI, 50_000) == IntervalAnswer(forward=False)
    # Back down: the agent's 10 Hz is restored, from the agent, and the GCS answered.
    assert merger.message_interval(MAVPROXY, GPI, 250_000) == IntervalAnswer(False, 10.0)
    # Stopping a message the agent needs is answered, and does not stop it.
    assert merger.message_interval(MAVPROXY, GPI, -1) == IntervalAnswer(forward=False)
    # A message nobody else wants is the GCS's own business.
    wind = mavlink2.MAVLINK_MSG_ID_WIND
    assert merger.message_interval(MAVPROXY, wind, 500_000) == IntervalAnswer(forward=True)
    assert merger.message_interval(MAVPROXY, wind, 0) == IntervalAnswer(forward=True)
    # The link came up again: the flight controller's rates are unknown, asked anew.
    merger.reset()
    assert merger.message_interval(QGC, GPI, 50_000) == IntervalAnswer(forward=True)
