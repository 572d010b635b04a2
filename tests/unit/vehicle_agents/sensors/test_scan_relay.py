"""The agent's scan timing and delivery: the flight controller's clock, the sensor's clock,
poses between reports, and the newest-first outbox with its bounded budget."""

from __future__ import annotations

import asyncio
import math
import random
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import pytest
from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from protocol.scans import FLAG_REPLAYED, decode_scan, encode_scan
from simulator.sensors.lidar import Lidar, LidarSpec, Pose
from simulator.wire.ydlidar import encode_beams
from simulator.world.obstacles import default_scene
from tests.support.scans import _frame
from vehicle_agents.sensors.fcu_time import FcuClock, PoseHistory, ask_timesync
from vehicle_agents.sensors.lidar.ydlidar import YdlidarParser
from vehicle_agents.sensors.relay import DiskBacklog, ScanOutbox
from vehicle_agents.sensors.turn_assembly import TurnAssembler


def _message(kind: str, boot_s: float, **fields: float) -> SimpleNamespace:
    return SimpleNamespace(get_type=lambda: kind, time_boot_ms=round(boot_s * 1000), **fields)


@pytest.mark.parametrize("rate", [1.0, 5.0])  # a real board; the simulator sped up 5 times
def test_the_flight_controllers_clock_is_found_through_late_arrivals(rate: float) -> None:
    rng = random.Random(1)
    clock = FcuClock()
    offset = 1234.5  # the agent's monotonic reading at the board's boot
    for i in range(300):
        arrived = offset + i * 0.05
        late = rng.expovariate(1 / 0.004)  # a few milliseconds, now and then more
        clock.add(arrived + late, (arrived - offset) * rate)
    for probe in (offset + 5.0, offset + 14.0):
        assert clock.to_fcu(probe) == pytest.approx((probe - offset) * rate, abs=0.002 * rate)


def test_a_reboot_starts_the_clock_again() -> None:
    clock = FcuClock()
    for i in range(50):
        clock.add(100.0 + i * 0.1, 500.0 + i * 0.1)
    clock.add(106.0, 0.1)
    assert clock.reboots == 1
    assert clock.to_fcu(106.0) == pytest.approx(0.1)


def test_poses_are_interpolated_between_reports_across_the_yaw_wrap() -> None:
    poses = PoseHistory(FcuClock(), monotonic=lambda: 0.0)
    for t, lat, yaw in ((1.0, -35.0, math.pi - 0.1), (1.1, -35.00001, -math.pi + 0.1)):
        poses.on_message(_message("GLOBAL_POSITION_INT", t, lat=lat * 1e7, lon=149e7, alt=5000))
        poses.on_message(_message("ATTITUDE", t, roll=0.0, pitch=0.0, yaw=yaw))
    middle = poses.at(1.05)
    assert middle is not None
    assert middle.lat == pytest.approx(-35.000005)
    assert abs(math.remainder(middle.yaw, 2 * math.pi)) == pytest.approx(math.pi)
    assert poses.at(1.2) is None  # never extrapolated
    assert poses.latest_time() == pytest.approx(1.1)


def test_turns_are_timed_by_the_least_delayed_packets() -> None:
    """Packets arrive late by a random few milliseconds, sometimes 50 ms; each turn's
    start still comes out within a couple of milliseconds."""
    rng = random.Random(2)
    lidar = Lidar(default_scene(), LidarSpec(noise_sigma_m=0.0, dropout=0.0))
    parser, assembler = YdlidarParser(), TurnAssembler()
    starts = []
    for step in range(200):  # 4 s
        t = step * 0.02
        beams = lidar.advance(Pose(t, 0.0, 0.0, 2.0, 0.0, 0.0, 0.0))
        if beams is None:
            continue
        late = rng.choice([0.0005, 0.002, 0.004, 0.05])
        for packet in parser.feed(encode_beams(beams, 10.0)):
            if (turn := assembler.add(packet, 100.0 + t + late)) is not None:
                starts.append(turn.start - 100.0)
    settled = starts[10:]  # after a second of packets
    assert all(s == pytest.approx(round(s * 10) / 10, abs=0.003) for s in settled)


def test_the_newest_scan_goes_first_then_the_backlog_oldest_first_as_replayed() -> None:
    async def run() -> None:
        outbox = ScanOutbox(budget=2)
        frames = [encode_scan(_frame()) for _ in range(4)]
        frames = [f[:8] + bytes([i]) + f[9:] for i, f in enumerate(frames)]  # seq 0..3
        for frame in frames:
            outbox.put(frame)
        assert outbox.dropped == 1  # seq 0: the budget holds two behind the newest
        sent = [decode_scan(await outbox.next_frame()) for _ in range(3)]
        assert [(s.seq, s.replayed) for s in sent] == [(3, False), (1, True), (2, True)]
        outbox.unsent(frames[3])  # the link dropped as it went: it waits again
        assert decode_scan(await outbox.next_frame()).flags & FLAG_REPLAYED

    asyncio.run(run())


def test_a_disk_backlog_survives_the_agent_and_keeps_its_order(tmp_path: Path) -> None:
    async def run() -> None:
        frames = [encode_scan(_frame()) for _ in range(5)]
        frames = [f[:8] + bytes([i]) + f[9:] for i, f in enumerate(frames)]
        first = ScanOutbox(budget=3, backlog=DiskBacklog(tmp_path / "v1.scans.sqlite"))
        for frame in frames:
            first.put(frame)  # an outage: nothing sent
        assert first.dropped == 1
        # The agent restarts: the backlog on disk is still there, oldest first, replayed.
        again = ScanOutbox(budget=3, backlog=DiskBacklog(tmp_path / "v1.scans.sqlite"))
        sent = [decode_scan(await again.next_frame()) for _ in range(3)]
        assert [(s.seq, s.replayed) for s in sent] == [(1, True), (2, True), (3, True)]
        again.unsent(frames[3])
        assert decode_scan(await again.next_frame()).seq == 3
        assert len(again) == 0

    asyncio.run(run())


def test_timesync_stamps_tighten_the_clock_and_a_companions_are_ignored() -> None:
    now = [0.0]
    poses = PoseHistory(FcuClock(), monotonic=lambda: now[0])
    offset = 50.0  # the agent's monotonic reading at the board's boot

    def attitude(board_s: float) -> None:  # the streams arrive 20 ms late, every one
        now[0] = offset + board_s + 0.020
        poses.on_message(_message("ATTITUDE", board_s, roll=0.0, pitch=0.0, yaw=0.0))

    for i in range(100):
        attitude(i * 0.1)
    assert poses.clock.to_fcu(offset + 5.0) == pytest.approx(5.0 - 0.020, abs=1e-6)
    # a companion computer's request, on its own clock: not the flight controller's
    now[0] = offset + 10.0
    poses.on_message(SimpleNamespace(get_type=lambda: "TIMESYNC", tc1=0, ts1=7_000 * 10**9))
    assert poses.timesync_ignored == 1
    # the flight controller's answers twice a second (tc1: its nanoseconds since boot),
    # 1 ms on the way, among the streams
    for i in range(100, 400):
        attitude(i * 0.1)
        if i % 5 == 0:
            board_s = i * 0.1 + 0.05
            now[0] = offset + board_s + 0.001
            answer = SimpleNamespace(get_type=lambda: "TIMESYNC", tc1=round(board_s * 1e9), ts1=1)
            poses.on_message(answer)
    assert poses.timesync_ignored == 1
    assert poses.clock.to_fcu(offset + 40.0) == pytest.approx(40.0 - 0.001, abs=2e-4)


def test_the_agent_asks_for_timesync_and_a_down_link_does_not_stop_it() -> None:
    async def run() -> list[Any]:
        sent: list[Any] = []
        tries = [0]
        enough = asyncio.Event()

        def send(message: Any) -> None:
            tries[0] += 1
            if tries[0] == 1:  # the first try: the link is down
                raise ConnectionError("flight controller link is down")
            sent.append(message)
            if len(sent) == 2:
                enough.set()

        asker = asyncio.create_task(ask_timesync(send, every_s=0.0, monotonic_ns=lambda: 42))
        await asyncio.wait_for(enough.wait(), 5)
        asker.cancel()
        return sent

    sent = asyncio.run(run())
    packed = [m.pack(mavlink2.MAVLink(None, srcSystem=255)) for m in sent]
    assert len(sent) >= 2
    assert {(m.tc1, m.ts1) for m in sent} == {(0, 42)}
    assert all(data[0] == 0xFD for data in packed)  # MAVLink 2 frames
