"""The agent's YDLIDAR parser on the simulator's byte stream, whole and corrupted: split and
merged packets, bad checksums, garbage. It counts what it throws away and never raises."""

from __future__ import annotations

import random
import struct

import pytest

from simulator.sensors.lidar import Lidar, LidarSpec, Pose
from simulator.wire.ydlidar import SCAN_RESPONSE, encode_beams, health, packet
from simulator.world.obstacles import default_scene
from vehicle_agents.sensors.lidar.common import Health, Packet
from vehicle_agents.sensors.lidar.ydlidar import YdlidarParser


def _stream(seconds: float = 0.5) -> bytes:
    lidar = Lidar(default_scene(), LidarSpec(), seed=5)
    out = bytearray()
    for i in range(round(seconds / 0.02) + 1):
        beams = lidar.advance(Pose(i * 0.02, 0.0, 0.0, 2.0, 0.0, 0.0, 0.5))
        if beams is not None:
            out += encode_beams(beams, 10.0)
    return bytes(out)


def _parse(chunks: list[bytes]) -> tuple[list[Packet], YdlidarParser]:
    parser = YdlidarParser()
    packets = [p for chunk in chunks for p in parser.feed(chunk)]
    return packets, parser


def _split(data: bytes, rng: random.Random) -> list[bytes]:
    chunks, at = [], 0
    while at < len(data):
        size = rng.choice([1, 2, 3, 7, 10, 64, 1000])
        chunks.append(data[at : at + size])
        at += size
    return chunks


def test_packets_split_anywhere_or_merged_parse_the_same() -> None:
    data = _stream()
    whole, parser = _parse([data])
    assert parser.stats.drops["bad_checksum"] == parser.stats.skipped_bytes == 0
    assert sum(len(p.distances_mm) for p in whole) == 3601  # 0 to 0.5 s of 7,200 samples/s
    assert sum(p.zero for p in whole) == 6
    assert {p.scan_hz for p in whole if p.zero} == {10.0}
    split, parser = _parse(_split(data, random.Random(1)))
    assert split == whole
    assert parser.stats.drops["bad_checksum"] == parser.stats.skipped_bytes == 0


def test_a_corrupted_packet_is_counted_and_the_rest_survive() -> None:
    good = [packet(0, [10.0, 10.5, 11.0], [1000, 2000, 3000]) for _ in range(10)]
    corrupted = list(good)
    flipped = bytearray(good[3])
    flipped[12] ^= 0x40  # a distance byte: the checksum no longer matches
    corrupted[3] = bytes(flipped)
    packets, parser = _parse([b"".join(corrupted)])
    assert len(packets) == 9
    assert parser.stats.drops["bad_checksum"] == 1
    assert packets[0].distances_mm == [1000, 2000, 3000]
    assert packets[0].angles_deg == pytest.approx([10.0, 10.5, 11.0])


def test_garbage_between_and_a_truncated_packet_are_skipped() -> None:
    one = packet(0, [90.0, 91.0], [1500, 1600])
    data = b"\x00\x13garbage" + one + one[:7] + b"\xaa" + one + b"\xaa\x55\x00\x00" + one
    packets, parser = _parse([data])
    assert [p.distances_mm for p in packets] == [[1500, 1600]] * 3
    assert parser.stats.skipped_bytes > 0
    assert parser.stats.drops["bad_checksum"] >= 1  # the truncated packet's header read as one


def _raw_packet(samples: bytes) -> bytes:
    """A packet with these sample bytes as they are (intensity included), checksummed."""
    count, fsa, lsa = len(samples) // 3, (64 << 1) | 1, (128 << 1) | 1
    checksum = 0x55AA ^ fsa ^ (count << 8) ^ lsa
    for i in range(0, len(samples), 3):
        checksum ^= samples[i] ^ (samples[i + 1] | samples[i + 2] << 8)
    return struct.pack("<HBBHHH", 0x55AA, 0, count, fsa, lsa, checksum) + samples


def test_a_header_pattern_inside_samples_does_not_lose_the_packet() -> None:
    one = _raw_packet(bytes([0xAA, 0x55, 0x10, 0x00, 0xAA, 0x55, 0xB4, 0x20, 0x03]))
    packets, parser = _parse([b"\xaa" + one + one])
    assert len(packets) == 2
    assert packets[0].distances_mm == [0x1055 >> 2, 0x55AA >> 2, 0x0320 >> 2]
    assert parser.stats.drops["bad_checksum"] == 0


def test_random_garbage_never_raises_and_memory_stays_bounded() -> None:
    rng = random.Random(7)
    data = _stream(0.2)
    noisy = bytearray(data)
    for _ in range(200):  # bit flips anywhere
        noisy[rng.randrange(len(noisy))] ^= 1 << rng.randrange(8)
    parser = YdlidarParser()
    for chunk in _split(bytes(noisy) + rng.randbytes(200_000), rng):
        parser.feed(chunk)
        assert len(parser._buffer) <= 64 * 1024 + 2048
    assert parser.stats.drops["bad_checksum"] > 0
    assert parser.stats.packets > 0


def test_the_answers_to_the_drivers_commands_are_read_not_counted_as_garbage() -> None:
    # What a T-mini Pro sends after stop, health and start: the health answer (here an
    # error), the start answer, then packets; and an answer of a kind the driver never asks.
    one = packet(0, [90.0, 91.0], [1500, 1600])
    data = health(2, 0x0102) + SCAN_RESPONSE + one + bytes([0xA5, 0x5A, 0x04, 0, 0, 0, 0x15]) + one
    for chunks in ([data], _split(data, random.Random(3)), [bytes([b]) for b in data]):
        packets, parser = _parse(chunks)
        assert [p.distances_mm for p in packets] == [[1500, 1600]] * 2
        assert parser.stats.responses == 2
        assert parser.health == Health(2, 0x0102)
        assert parser.stats.skipped_bytes == 7  # the unknown answer's descriptor
        assert parser.stats.drops["bad_checksum"] == 0
