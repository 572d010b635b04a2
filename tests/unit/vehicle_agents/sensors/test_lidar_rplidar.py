"""The agent's RPLIDAR parser on byte streams built here, field by field, from Slamtec's
published interface protocol (not from the simulator's encoder, so a mistake shared by
both cannot hide): descriptors, GET_INFO and GET_HEALTH answers, the standard scan's
5-byte nodes, the express scan's legacy, dense and ultra capsules; cuts and corrupted
bytes cost what they hit and are counted."""

from __future__ import annotations

import math
import struct

import pytest

from vehicle_agents.sensors.lidar.common import Health
from vehicle_agents.sensors.lidar.models import MODELS, start_commands
from vehicle_agents.sensors.lidar.rplidar import (
    DENSE_CAPSULE,
    LEGACY_CAPSULE,
    STANDARD,
    ULTRA_CAPSULE,
    RplidarParser,
    express_scan,
    motor_pwm,
    request,
)

# The protocol document's examples: GET_HEALTH is "A5 52"; its answer "A5 5A 03 00 00 00
# 06" then status and error code; SCAN's answer "A5 5A 05 00 00 40 81"; GET_INFO's "A5 5A
# 14 00 00 00 04" then 20 bytes.
HEALTH_ANSWER = bytes.fromhex("a55a0300000006")
SCAN_ANSWER = bytes.fromhex("a55a0500004081")
INFO_ANSWER = bytes.fromhex("a55a1400000004")


def _descriptor(length: int, kind: int) -> bytes:
    return b"\xa5\x5a" + struct.pack("<IB", length | 1 << 30, kind)


def _node(start: bool, quality: int, angle_q6: int, distance_q2: int) -> bytes:
    return struct.pack("<BHH", (1 if start else 2) | quality << 2, angle_q6 << 1 | 1, distance_q2)


def _capsule(start_q6: int, body: bytes, new: bool = False) -> bytes:
    rest = struct.pack("<H", start_q6 | (0x8000 if new else 0)) + body
    check = 0
    for byte in rest:
        check ^= byte
    return bytes([0xA0 | check & 0xF, 0x50 | check >> 4]) + rest


def _feed_bytewise(parser: RplidarParser, data: bytes) -> list:
    return [p for i in range(len(data)) for p in parser.feed(data[i : i + 1])]


def test_requests_carry_the_documented_checksum() -> None:
    assert request(0x52) == bytes.fromhex("a552")
    assert request(0x25) == bytes.fromhex("a525")
    # EXPRESS_SCAN, working mode 0: A5 82 05 00 00 00 00 00, checksum = XOR of all = 0x22
    assert express_scan(0) == bytes.fromhex("a58205000000000022")
    # SET_MOTOR_PWM 660 (0x0294): A5 F0 02 94 02, checksum 0xA5^0xF0^0x02^0x94^0x02 = 0xC1
    assert motor_pwm(660) == bytes.fromhex("a5f0029402c1")
    a2 = start_commands(MODELS["rplidar-a2"])
    assert a2 == [
        bytes.fromhex("a550"),
        bytes.fromhex("a552"),
        motor_pwm(660),
        bytes.fromhex("a520"),
    ]


def test_info_and_health_answers_are_read() -> None:
    info = bytes([0x18, 29, 1, 7]) + bytes(range(16))
    data = INFO_ANSWER + info + HEALTH_ANSWER + bytes([2, 0x34, 0x12])
    for parser_feed in ("whole", "bytewise"):
        parser = RplidarParser(scan=None)
        if parser_feed == "whole":
            assert parser.feed(data) == []
        else:
            assert _feed_bytewise(parser, data) == []
        assert parser.health == Health(2, 0x1234)
        assert parser.info is not None
        assert parser.info.name == "RPLIDAR A1"
        assert parser.info.firmware == "1.29"
        assert parser.info.hardware == 7
        assert parser.info.serial == bytes(range(16)).hex().upper()
        assert parser.stats.responses == 2
        assert parser.stats.skipped_bytes == 0


def test_standard_nodes_decode_to_a_hundredth_of_a_degree_and_a_millimetre() -> None:
    nodes = [
        (True, 15, 5761, 4937),  # 90.015625 deg, 1234.25 mm: the first of a turn
        (False, 47, 5793, 400),  # 90.515625 deg, 100 mm
        (False, 0, 23039, 0),  # 359.984375 deg, no return
        (True, 10, 32, 65535),  # 0.5 deg, 16383.75 mm: the next turn
    ]
    data = SCAN_ANSWER + b"".join(_node(*n) for n in nodes)
    for packets in (RplidarParser(scan=None).feed(data), _feed_bytewise(RplidarParser(None), data)):
        angles = [a for p in packets for a in p.angles_deg]
        distances = [d for p in packets for d in p.distances_mm]
        assert angles == pytest.approx([90.015625, 90.515625, 359.984375, 0.5], abs=0.01)
        assert distances == [1234, 100, 0, 16384]
        starts = [p.angles_deg[0] for p in packets if p.zero]
        assert starts == [pytest.approx(90.015625), pytest.approx(0.5)]


def test_nodes_with_broken_check_bits_are_skipped_and_counted() -> None:
    good = _node(False, 20, 64 * 45, 4000)
    bad_s = bytes([0x03]) + good[1:]  # S and !S both set
    bad_check = good[:1] + bytes([good[1] & 0xFE]) + good[2:]  # the check bit cleared
    parser = RplidarParser(STANDARD)
    packets = parser.feed(good + bad_s[:1] + good + bad_check[:2] + good)
    assert [d for p in packets for d in p.distances_mm] == [1000, 1000, 1000]
    assert parser.stats.drops["bad_check_bits"] == 3


def _legacy_body(distances: list[int], offsets_q3: list[int]) -> bytes:
    body = b""
    for k in range(16):
        o1, o2 = offsets_q3[2 * k], offsets_q3[2 * k + 1]
        d1 = distances[2 * k] << 2 | o1 >> 4
        d2 = distances[2 * k + 1] << 2 | o2 >> 4
        body += struct.pack("<HHB", d1, d2, (o1 & 0xF) | (o2 & 0xF) << 4)
    return body


def test_legacy_express_capsules_interpolate_between_start_angles_less_the_compensation() -> None:
    distances = [1000 + 37 * i for i in range(32)]
    offsets = [(i * 5) % 64 for i in range(32)]  # 0 .. 7.875 degrees, in 1/8 degree
    first = _capsule(64 * 350, _legacy_body(distances, offsets), new=True)  # 350 deg
    second = _capsule(64 * 6, _legacy_body([0] * 32, [0] * 32))  # 6 deg: 16 deg on, past 0
    third = _capsule(64 * 22, _legacy_body([0] * 32, [0] * 32))
    data = _descriptor(84, LEGACY_CAPSULE) + first + second + third
    for packets in (RplidarParser(None).feed(data), _feed_bytewise(RplidarParser(None), data)):
        angles = [a for p in packets for a in p.angles_deg]
        got = [d for p in packets for d in p.distances_mm]
        assert got[:32] == distances
        expected = [(350.0 + i * 0.5 - offsets[i] / 8.0) % 360.0 for i in range(32)]
        assert angles[:32] == pytest.approx(expected, abs=0.01)
        assert len(got) == 64  # the third capsule waits for a fourth's angle
        # a turn starts where the angle passes 0 (about sample 20: 360 - 350 = 10 = 20 x 0.5,
        # give or take the compensations)
        zero = [p for p in packets if p.zero]
        assert len(zero) == 1
        assert zero[0].angles_deg[0] < 8.0


def test_dense_capsules_are_40_evenly_spaced_millimetre_distances() -> None:
    distances = [500 + 101 * i for i in range(40)]
    data = (
        _descriptor(84, DENSE_CAPSULE)
        + _capsule(64 * 100, struct.pack("<40H", *distances))
        + _capsule(64 * 110 + 32, struct.pack("<40H", *[0] * 40))  # 10.5 deg on
    )
    parser = RplidarParser(None)
    packets = parser.feed(data)
    assert [d for p in packets for d in p.distances_mm] == distances
    expected = [100.0 + i * 10.5 / 40 for i in range(40)]
    assert [a for p in packets for a in p.angles_deg] == pytest.approx(expected, abs=0.01)


def _offset_deg(distance_mm: int) -> float:
    """Slamtec's triangulation offset for ultra samples, restated from its SDK: 7.5 degrees
    under 50 mm, else 8 degrees less k2 * 64 and k2^3 / 98304 (radians << 16), where k2 =
    98361 // (distance in 1/4 mm)."""
    if distance_mm * 4 < 200:
        q16 = int(7.5 * math.pi * 65536 / 180)
    else:
        k2 = 98361 // (distance_mm * 4)
        q16 = int(8 * math.pi * 65536 / 180) - k2 * 64 - k2**3 // 98304
    return math.degrees(q16 / 65536)


def _ultra_cabin(major_scaled: int, predict1: int, predict2: int) -> bytes:
    return struct.pack("<I", major_scaled | (predict1 & 0x3FF) << 12 | (predict2 & 0x3FF) << 22)


def test_ultra_capsules_unpack_the_variable_bit_scale_and_the_predictions() -> None:
    # cabin 0: major 1000 mm (scaled 512 + 488 / 2 = 756, level 1), predict1 +5 -> 1010 mm,
    #   predict2 -3 on the next major (1100 mm, scaled 806, level 1) -> 1094 mm;
    # cabin 1: major 1100, predict1 0x1FF (no return), predict2 on cabin 2's major:
    # cabin 2: major 20000 mm (scaled 3328 + 3616 / 16 = 3554, level 4): predict2 of cabin 1
    #   -2 -> 20000 - 32 = 19968 mm; cabin 2 predict1 +1 -> 20016; predict2 on cabin 3 = 0
    #   (major 0, no return): -0x200 is "no return".
    # cabin 3: major 0 with a next major of 300 mm: its predict1 +4 counts from that.
    cabins = [
        _ultra_cabin(756, 5, -3),
        _ultra_cabin(806, 0x1FF, -2),
        _ultra_cabin(3554, 1, -512),
        _ultra_cabin(0, 4, 0),
    ] + [_ultra_cabin(300, 0, 0)] * 28
    expected = [1000, 1010, 1094, 1100, 0, 19968, 20000, 20016, 0, 0, 304, 300]
    first = _capsule(64 * 200, b"".join(cabins), new=True)
    second = _capsule(64 * 248, b"".join([_ultra_cabin(300, 0, 0)] * 32))  # 48 deg on
    parser = RplidarParser(ULTRA_CAPSULE)
    packets = parser.feed(first + second)
    distances = [d for p in packets for d in p.distances_mm]
    angles = [a for p in packets for a in p.angles_deg]
    assert distances[:12] == expected
    assert len(distances) == 96
    nominal = [200.0 + i * 0.5 for i in range(96)]
    assert angles == pytest.approx(
        [(a - _offset_deg(d)) % 360 for a, d in zip(nominal, distances, strict=True)], abs=0.01
    )
    assert parser.stats.skipped_bytes == 0


def test_varbitscale_bands_meet_at_their_edges() -> None:
    from vehicle_agents.sensors.lidar.rplidar import varbitscale

    assert varbitscale(511) == (511, 0)
    assert varbitscale(512) == (512, 1)
    assert varbitscale(1280) == (2048, 2)
    assert varbitscale(1792) == (4096, 3)
    assert varbitscale(3328) == (16384, 4)
    assert varbitscale(4095) == (16384 + 767 * 16, 4)


def test_a_corrupted_capsule_is_counted_and_its_neighbours_decode() -> None:
    capsules = [
        _capsule(64 * (10 * i % 360), struct.pack("<40H", *[1000 + i] * 40)) for i in range(6)
    ]
    broken = bytearray(capsules[2])
    broken[30] ^= 0x10
    parser = RplidarParser(DENSE_CAPSULE)
    packets = parser.feed(b"".join(capsules[:2]) + bytes(broken) + b"".join(capsules[3:]))
    got = sorted({d for p in packets for d in p.distances_mm})
    # capsule 1 needs capsule 2's angle and capsule 2 is lost: 0 and 3, 4 decode (1 is not
    # decoded against capsule 3's angle: its samples would be spread over two capsules' span)
    assert got == [1000, 1003, 1004]
    assert parser.stats.drops["bad_checksum"] >= 1


def test_a_new_scan_answer_switches_the_format_mid_stream() -> None:
    nodes = b"".join(_node(i == 0, 10, 64 * i, 4 * 2000) for i in range(5))
    dense = _capsule(64 * 5, struct.pack("<40H", *[700] * 40)) + _capsule(
        64 * 25, struct.pack("<40H", *[0] * 40)
    )
    parser = RplidarParser(None)
    packets = parser.feed(
        b"\x00\x01" + SCAN_ANSWER + nodes + _descriptor(84, DENSE_CAPSULE) + dense
    )
    distances = [d for p in packets for d in p.distances_mm]
    assert distances == [2000] * 5 + [700] * 40
    assert parser.scan == DENSE_CAPSULE
    assert parser.stats.responses == 2
