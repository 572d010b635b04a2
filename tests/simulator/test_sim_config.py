"""Command line, clocks and stream scheduling of the simulator."""

from __future__ import annotations

import pytest

import common.geodesy
from simulator import (
    DEFAULT_HOME,
    Copter,
    GeoPoint,
    ListenAddress,
    LocalFrame,
    ManualClock,
    SimClock,
    SimulatorConfig,
    main,
)
from simulator.config import parse_args
from simulator.mavlink.streams import StreamSchedule


def test_defaults() -> None:
    config = parse_args([])
    assert config == SimulatorConfig()
    assert str(config.listen) == "tcp:127.0.0.1:5760"
    assert config.system_id == 1
    assert config.home == GeoPoint(-35.363262, 149.165237, 584.0) == DEFAULT_HOME
    assert config.speedup == 1.0
    assert config.log_level == "INFO"


def test_all_flags() -> None:
    config = parse_args(
        [
            "--listen",
            "udp:0.0.0.0:14550",
            "--system-id",
            "42",
            "--home",
            "47.397742,8.545594,488",
            "--speedup",
            "5",
            "--log-level",
            "debug",
        ]
    )
    assert config.listen == ListenAddress("udp", "0.0.0.0", 14550)
    assert config.system_id == 42
    assert config.home == GeoPoint(47.397742, 8.545594, 488.0)
    assert config.speedup == 5.0
    assert config.log_level == "DEBUG"


def test_southern_home_as_separate_argument() -> None:
    """The launcher passes ``--home`` and a value starting with a minus sign."""
    config = parse_args(["--home", "-35.3632620,149.1652370,584.0", "--speedup", "5"])
    assert config.home == GeoPoint(-35.363262, 149.165237, 584.0)
    assert config.speedup == 5.0
    assert parse_args(["--home=-1,-2,3"]).home == GeoPoint(-1.0, -2.0, 3.0)


@pytest.mark.parametrize(
    ("text", "expected"),
    [
        ("tcp:127.0.0.1:5760", ListenAddress("tcp", "127.0.0.1", 5760)),
        ("udp::14550", ListenAddress("udp", "0.0.0.0", 14550)),
        ("tcp:[::1]:5760", ListenAddress("tcp", "::1", 5760)),
        ("tcp:localhost:0", ListenAddress("tcp", "localhost", 0)),
    ],
)
def test_listen_addresses(text: str, expected: ListenAddress) -> None:
    assert ListenAddress.parse(text) == expected


def test_listen_address_round_trips() -> None:
    for text in ("tcp:127.0.0.1:5760", "udp:[::1]:14550"):
        assert str(ListenAddress.parse(text)) == text


@pytest.mark.parametrize("text", ["serial:/dev/ttyS0", "tcp:5760", "udp:host:port", "tcp:h:70000"])
def test_bad_listen_addresses(text: str) -> None:
    with pytest.raises(ValueError, match=r"."):
        ListenAddress.parse(text)


@pytest.mark.parametrize(
    "argv",
    [
        ["--speedup", "0"],
        ["--speedup", "101"],
        ["--speedup", "fast"],
        ["--system-id", "0"],
        ["--system-id", "256"],
        ["--home", "1,2"],
        ["--home"],
        ["--home", "91,0,0"],
        ["--listen", "tcp:nowhere"],
        ["--log-level", "chatty"],
        ["--unknown"],
        ["--camera-component", "--camera-model", "4.8,3.6,320,240,5.4"],  # no photo server
        ["--camera-folder", "/tmp/card"],  # no camera model to render with
        ["--camera-model", "4.8,3.6,320"],
    ],
)
def test_bad_arguments_exit_2(argv: list[str], capsys: pytest.CaptureFixture[str]) -> None:
    assert main(argv) == 2
    assert "usage:" in capsys.readouterr().err


def test_help_exits_0(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["--help"]) == 0
    out = capsys.readouterr().out
    for flag in ("--listen", "--system-id", "--home", "--speedup", "--log-level"):
        assert flag in out


def test_config_validates_itself() -> None:
    with pytest.raises(ValueError, match="speed-up"):
        SimulatorConfig(speedup=0.0)
    with pytest.raises(ValueError, match="system id"):
        SimulatorConfig(system_id=300)


def test_sim_clock_scales_wall_time() -> None:
    wall = [100.0]
    clock = SimClock(5.0, monotonic=lambda: wall[0])
    assert clock.now() == 0.0
    wall[0] = 102.5
    assert clock.now() == pytest.approx(12.5)
    with pytest.raises(ValueError, match="speed-up"):
        SimClock(0.0)


def test_manual_clock() -> None:
    clock = ManualClock()
    clock.advance(1.5)
    assert clock.now() == 1.5
    with pytest.raises(ValueError, match="backwards"):
        clock.advance(-1.0)


def test_local_frame_round_trip() -> None:
    copter = Copter(DEFAULT_HOME)
    point = copter.geo_of(north=1234.5, east=-678.9, up=12.0)
    assert point.alt == pytest.approx(596.0)
    assert copter.ne_of(point.lat, point.lon) == pytest.approx((1234.5, -678.9), abs=1e-6)
    # WGS84, not a sphere: 1e-5 degree of latitude there is 1.10947 m on the ellipsoid
    # (pyproj's Geod), scaled by (R + 584 m) / R at the home's height.
    north, east = copter.ne_of(DEFAULT_HOME.lat + 1e-5, DEFAULT_HOME.lon)
    assert north == pytest.approx(1.1094724 * (1 + 584.0 / 6_371_000), abs=1e-6)
    assert east == pytest.approx(0.0, abs=1e-9)
    assert LocalFrame is common.geodesy.LocalFrame


def test_stream_schedule() -> None:
    schedule = StreamSchedule({0: 1.0, 33: 10.0}, now=0.0)
    assert schedule.due(0.0) == [0, 33]  # everything at once on connect
    assert schedule.due(0.05) == []
    assert schedule.due(0.1) == [33]
    sent = sum(33 in schedule.due(t / 100.0) for t in range(11, 101))
    assert sent == 9
    schedule.set_interval(0, None, now=1.0)
    assert schedule.interval(0) is None
    assert 0 not in schedule.due(5.0)
    schedule.reset_interval(0, now=5.0)
    assert schedule.interval(0) == 1.0
    schedule.set_interval(24, 0.0001, now=5.0)  # clamped to 100 Hz
    assert schedule.interval(24) == 0.01


def test_stream_schedule_does_not_burst_after_a_stall() -> None:
    schedule = StreamSchedule({33: 10.0}, now=0.0)
    schedule.due(0.0)
    assert schedule.due(5.0) == [33]
    assert schedule.due(5.05) == []
    assert schedule.due(5.1) == [33]


def test_stream_schedule_catches_up_a_short_delay() -> None:
    # at a speed-up a tick held up a moment is tenths of a sim second: the messages
    # missed go at the next ticks, keeping the rate, and the schedule says when
    schedule = StreamSchedule({33: 10.0}, now=0.0)
    assert schedule.next_due() == 0.0
    schedule.due(0.0)
    assert schedule.next_due() == pytest.approx(0.1)
    assert schedule.due(0.45) == [33]
    assert schedule.due(0.451) == [33]
    assert schedule.due(0.452) == [33]
    assert schedule.due(0.453) == [33]
    assert schedule.due(0.454) == []
    assert schedule.next_due() == pytest.approx(0.5)
    assert StreamSchedule({}, now=0.0).next_due() is None


def test_sim_clock_holds_through_a_stall() -> None:
    wall = [100.0]
    clock = SimClock(10.0, monotonic=lambda: wall[0], max_step_s=0.05)
    wall[0] = 100.04
    assert clock.now() == pytest.approx(0.4)
    wall[0] = 100.54  # held up half a second: a twentieth counts
    assert clock.now() == pytest.approx(0.9)
    wall[0] = 100.55
    assert clock.now() == pytest.approx(1.0)


def test_send_soon() -> None:
    schedule = StreamSchedule({0: 1.0}, now=0.0)
    schedule.due(0.0)
    schedule.send_soon(0, now=0.3)
    assert schedule.due(0.3) == [0]
