from __future__ import annotations

import dataclasses
import subprocess
import sys
from pathlib import Path
from types import ModuleType

import pytest

from backend.exports import ExportEvent, ExportSample, sample_position, tlog_chunks
from tests.support.mavutil_state import mavutil_in_mavlink2, read_tlog
from tests.unit.exports import flight_data
from tests.unit.exports.flight_data import T0, events, flight, samples


@pytest.fixture
def mavutil(monkeypatch: pytest.MonkeyPatch) -> ModuleType:
    return mavutil_in_mavlink2(monkeypatch)


def _write(path: Path, chunks: list[bytes]) -> Path:
    with path.open("wb") as file:
        for chunk in chunks:
            file.write(chunk)
    return path


def _by_time(flight_samples: list[ExportSample]) -> dict[int, ExportSample]:
    return {round(s.time * 1e6): s for s in flight_samples}


def test_positions_read_back_with_their_times(tmp_path: Path, mavutil: ModuleType) -> None:
    flight_samples = samples()
    positioned = [s for s in flight_samples if sample_position(s) is not None]
    path = _write(tmp_path / "f.tlog", list(tlog_chunks(flight(), flight_samples, events())))

    messages = read_tlog(mavutil, path)

    assert not [m for m in messages if m.get_type() == "BAD_DATA"]
    positions = [m for m in messages if m.get_type() == "GLOBAL_POSITION_INT"]
    assert len(positions) == len(positioned)
    for message, sample in zip(positions, positioned, strict=True):
        assert sample.lat is not None
        assert sample.lon is not None
        assert sample.alt_msl is not None
        assert sample.alt_rel is not None
        assert sample.heading_deg is not None
        assert message._timestamp == pytest.approx(sample.time, abs=1e-6)
        assert message.get_srcSystem() == 3
        assert message.lat == round(sample.lat * 1e7)
        assert message.lon == round(sample.lon * 1e7)
        assert message.alt == round(sample.alt_msl * 1000)
        assert message.relative_alt == round(sample.alt_rel * 1000)
        assert message.hdg == round(sample.heading_deg * 100) % 36000
        assert message.time_boot_ms == round((sample.time - T0) * 1000)
    timestamps = [m._timestamp for m in messages]
    assert timestamps == sorted(timestamps)
    for kind in ("GPS_RAW_INT", "VFR_HUD", "SYS_STATUS"):
        assert sum(m.get_type() == kind for m in messages) == len(flight_samples)


def test_heartbeats_decode_to_the_mode_names(tmp_path: Path, mavutil: ModuleType) -> None:
    flight_samples = samples(57)  # modes change at 1.9 s and 3.8 s, disarmed at 5.2 s
    path = _write(tmp_path / "f.tlog", list(tlog_chunks(flight(), flight_samples, [])))

    heartbeats = [m for m in read_tlog(mavutil, path) if m.get_type() == "HEARTBEAT"]

    samples_at = _by_time(flight_samples)
    for heartbeat in heartbeats:
        sample = samples_at[round(heartbeat._timestamp * 1e6)]
        assert mavutil.mode_string_v10(heartbeat) == sample.mode
        assert bool(heartbeat.base_mode & 128) == sample.armed  # MAV_MODE_FLAG_SAFETY_ARMED
    decoded = {mavutil.mode_string_v10(h) for h in heartbeats}
    assert decoded == {"STABILIZE", "GUIDED", "LAND"}
    # one a second of log time, and one at each change of mode or arming
    times = [round(h._timestamp - T0, 3) for h in heartbeats]
    assert times == [0.0, 1.0, 1.9, 2.9, 3.8, 4.8, 5.2]


@pytest.mark.parametrize(
    ("autopilot", "vehicle_type", "modes"),
    [
        ("px4", "multirotor", ("POSCTL", "MISSION", "RTL", "OFFBOARD")),
        ("ardupilot", "rover", ("MANUAL", "HOLD", "AUTO")),
        ("ardupilot", "fixed_wing", ("FBWA", "CRUISE", "RTL")),
        ("generic", "multirotor", ("LOITER", "Mode(99)")),
    ],
)
def test_modes_of_other_autopilots_and_vehicles(
    tmp_path: Path,
    mavutil: ModuleType,
    autopilot: str,
    vehicle_type: str,
    modes: tuple[str, ...],
) -> None:
    flight_samples = samples(len(modes) * 10, modes)
    chunks = tlog_chunks(flight(autopilot, vehicle_type), flight_samples, [])
    path = _write(tmp_path / "f.tlog", list(chunks))

    heartbeats = [m for m in read_tlog(mavutil, path) if m.get_type() == "HEARTBEAT"]

    assert {mavutil.mode_string_v10(h) for h in heartbeats} == set(modes)


def test_events_are_statustexts_merged_in_time_order(tmp_path: Path, mavutil: ModuleType) -> None:
    path = _write(tmp_path / "f.tlog", list(tlog_chunks(flight(), samples(), events())))

    texts = [m for m in read_tlog(mavutil, path) if m.get_type() == "STATUSTEXT"]

    assert [(t.text, t.severity) for t in texts] == [
        ("PreArm: before take-off", 4),
        ("Armed", 6),
        ("Mode GUIDED", 6),  # no severity: MAV_SEVERITY_INFO
        ("x" * 50, 2),  # truncated to the field's 50 characters
    ]
    assert [t._timestamp for t in texts] == pytest.approx(
        [T0 - 1.0, T0 + 0.1, T0 + 4.04, T0 + 99.0], abs=1e-6
    )


@pytest.mark.parametrize(
    ("text", "logged"),
    [
        ("mode STABILIZE → GUIDED", "mode STABILIZE -> GUIDED"),  # the hub's mode event
        ("Caméra prête", "Camera prete"),
        ("GPS 不好", "GPS ??"),
        ("→" * 30, "->" * 25),  # 50 bytes, the field's size
    ],
)
def test_a_statustext_is_ascii_as_mavlink_readers_decode_it(
    tmp_path: Path, mavutil: ModuleType, text: str, logged: str
) -> None:
    event = ExportEvent(time=T0 + 1.0, kind="mode", severity=None, text=text)
    path = _write(tmp_path / "f.tlog", list(tlog_chunks(flight(), samples(), [event])))

    (message,) = [m for m in read_tlog(mavutil, path) if m.get_type() == "STATUSTEXT"]

    assert message.text == logged


def test_mavlogdump_reads_the_log(tmp_path: Path) -> None:
    flight_samples = samples()
    positioned = [s for s in flight_samples if sample_position(s) is not None]
    path = _write(tmp_path / "f.tlog", list(tlog_chunks(flight(), flight_samples, events())))

    dump = subprocess.run(
        [
            sys.executable,
            str(Path(sys.executable).parent / "mavlogdump.py"),
            "--types",
            "GLOBAL_POSITION_INT",
            str(path),
        ],
        capture_output=True,
        text=True,
        check=True,
        timeout=60,
    )

    lines = [line for line in dump.stdout.splitlines() if line.strip()]
    assert len(lines) == len(positioned)
    assert all("GLOBAL_POSITION_INT" in line for line in lines)


def test_chunks_hold_many_records() -> None:
    chunks = list(tlog_chunks(flight(), samples(2000), [], chunk_bytes=16 * 1024))

    assert 5 < len(chunks) < 30
    assert all(len(chunk) >= 16 * 1024 for chunk in chunks[:-1])


def test_empty_flight_gives_an_empty_log() -> None:
    assert b"".join(tlog_chunks(flight(), [], [])) == b""


@pytest.mark.parametrize("extreme", [1e308, -1e308, 3.5e38, 1e19, -1e19])
def test_any_stored_value_is_written_never_an_exception(
    tmp_path: Path, mavutil: ModuleType, extreme: float
) -> None:
    """A hub that took impossible samples stored them (an altitude of 1e308); packing
    one raised (OverflowError) and the export ended with nothing written. Each is written
    clamped to its field, or as MAVLink's unknown where a float32 cannot hold it."""
    base = flight_data.sample(10)
    wild = dataclasses.replace(
        base,
        alt_msl=extreme,
        alt_rel=extreme,
        heading_deg=extreme,
        groundspeed=extreme,
        climb_rate=extreme,
        battery_voltage=extreme,
        battery_remaining=extreme,
    )
    path = _write(tmp_path / "wild.tlog", list(tlog_chunks(flight(), [base, wild], [])))
    messages = read_tlog(mavutil, path)
    assert [m.get_type() for m in messages].count("VFR_HUD") == 2
