"""Refused telemetry samples: counted one by one, recorded as runs of consecutive numbers
at most once per interval, and logged at most once per interval."""

from __future__ import annotations

import logging

import pytest

from backend.realtime.sample_refusals import SampleRefusals

LAT = [("lat", "lat 91 is outside -90..90")]
ALT = [("alt_msl", "alt_msl 1e+308 is outside -1000..100000")]


class Clock:
    def __init__(self) -> None:
        self.now = 100.0

    def __call__(self) -> float:
        return self.now


def test_consecutive_refusals_make_one_run_until_the_next_good_sample() -> None:
    refusals = SampleRefusals("v1", interval_s=1.0, clock=Clock())
    assert refusals.refuse("s1", 3, LAT) is None
    assert refusals.refuse("s1", 4, ALT) is None
    run = refusals.flush()
    assert run is not None
    assert (run.stream_id, run.kind, run.first_seq, run.last_seq) == ("s1", "telemetry", 3, 4)
    assert run.refused
    assert "lat 91 is outside -90..90" in run.reason
    assert refusals.flush() is None


def test_a_run_ends_at_a_jump_another_stream_or_the_interval() -> None:
    clock = Clock()
    refusals = SampleRefusals("v1", interval_s=1.0, clock=clock)
    refusals.refuse("s1", 1, LAT)
    jumped = refusals.refuse("s1", 5, LAT)
    assert jumped is not None
    assert (jumped.first_seq, jumped.last_seq) == (1, 1)
    other = refusals.refuse("old", 6, LAT)
    assert other is not None
    assert (other.stream_id, other.first_seq) == ("s1", 5)
    clock.now += 1.0
    late = refusals.refuse("old", 7, LAT)
    assert late is not None
    assert (late.stream_id, late.first_seq, late.last_seq) == ("old", 6, 6)


def test_refusals_are_logged_at_most_once_per_interval(caplog: pytest.LogCaptureFixture) -> None:
    clock = Clock()
    refusals = SampleRefusals("v1", interval_s=1.0, clock=clock)
    with caplog.at_level(logging.WARNING, "backend.realtime.sample_refusals"):
        for seq in range(40):  # 5 s at 8 Hz
            refusals.refuse("s1", seq, LAT)
            clock.now += 0.125
    assert len(caplog.records) == 5
    assert "refused 8 sample(s) of v1" in caplog.records[1].getMessage()
