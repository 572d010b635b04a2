"""The agent's YDLIDAR (2-byte samples, the X4's intercept correction, telling 2- from
3-byte samples) and LDROBOT parsers on byte streams built here from the manufacturers'
published formats, field by field (the simulator's encoders are tested against them in
tests/simulator/outputs/test_sim_lidar_formats.py)."""

from __future__ import annotations

import math
import struct

import pytest

from vehicle_agents.sensors.lidar.ldlidar import CRC_TABLE, LdlidarParser, crc8
from vehicle_agents.sensors.lidar.ydlidar import YdlidarParser


def _yd_packet(ct: int, fsa_q6: int, lsa_q6: int, words: list[int]) -> bytes:
    """X4 development manual: PH AA 55, CT, LSN, FSA, LSA, CS, Si (u16); CS = XOR of the
    u16 words PH, CT|LSN<<8, FSA, LSA and each Si."""
    fsa, lsa = fsa_q6 << 1 | 1, lsa_q6 << 1 | 1
    cs = 0x55AA ^ (ct | len(words) << 8) ^ fsa ^ lsa
    for word in words:
        cs ^= word
    return struct.pack(f"<HBBHHH{len(words)}H", 0x55AA, ct, len(words), fsa, lsa, cs, *words)


def _ang_correct(distance: float) -> float:
    """The X4 manual's AngCorrect, in degrees."""
    return (
        0.0
        if distance == 0
        else math.degrees(math.atan(21.8 * (155.3 - distance) / (155.3 * distance)))
    )


def test_x4_packets_decode_with_the_manuals_second_level_angle_correction() -> None:
    # the manual's method: Distance_i = S_i / 4; Angle_i = FSA/64 + (LSA - FSA)/64 / (LSN - 1)
    # * (i - 1) + AngCorrect_i
    words = [4 * 100, 4 * 155, 0, 4 * 1000, 4 * 8000]
    fsa_q6, lsa_q6 = 64 * 10 + 16, 64 * 12 + 16  # 10.25 .. 12.25 degrees
    data = _yd_packet(1, 0, 0, [0]) + _yd_packet(0, fsa_q6, lsa_q6, words)
    parser = YdlidarParser(sample_bytes=2, intercept=True)
    packets = parser.feed(data)
    assert [p.zero for p in packets] == [True, False]
    assert packets[1].distances_mm == [100, 155, 0, 1000, 8000]
    expected = [10.25 + 0.5 * i + _ang_correct(d) for i, d in enumerate([100, 155, 0, 1000, 8000])]
    assert packets[1].angles_deg == pytest.approx(expected, abs=0.01)
    assert _ang_correct(1000) == pytest.approx(-6.76, abs=0.01)  # what a metre away loses
    assert parser.stats.drops == {}


def test_g4_samples_without_correction_and_distances_to_the_millimetre() -> None:
    words = [4 * 3333 + 3, 4 * 16383]  # the low 2 bits are below a millimetre
    parser = YdlidarParser(sample_bytes=2)
    (packet,) = parser.feed(_yd_packet(0, 64 * 359, 64 * 359 + 32, words))
    assert packet.distances_mm == [3333, 16383]
    assert packet.angles_deg == pytest.approx([359.0, 359.5], abs=0.01)


def test_an_unknown_sample_size_is_told_by_the_checksum_and_kept() -> None:
    two = _yd_packet(0, 64 * 20, 64 * 21, [4 * 500, 4 * 600, 4 * 700])
    # the same with 3-byte samples (intensity byte, then the u16): CS covers the intensity
    three_words = [(4 * d) for d in (500, 600, 700)]
    fsa, lsa = (64 * 20) << 1 | 1, (64 * 21) << 1 | 1
    cs = 0x55AA ^ (3 << 8) ^ fsa ^ lsa
    body = b""
    for word in three_words:
        cs ^= 90 ^ word
        body += bytes([90]) + struct.pack("<H", word)
    three = struct.pack("<HBBHHH", 0x55AA, 0, 3, fsa, lsa, cs) + body
    for stream, size in ((two * 5, 2), (three * 5, 3)):
        parser = YdlidarParser(sample_bytes=None)
        packets = [p for i in range(len(stream)) for p in parser.feed(stream[i : i + 1])]
        assert [p.distances_mm for p in packets] == [[500, 600, 700]] * 5
        assert parser.sample_bytes == size
        assert parser.stats.drops["bad_checksum"] == 0


def test_the_ldrobot_crc_table_is_the_manuals() -> None:
    # The LD06/LD19 development manual's CrcTable starts 0x00, 0x4d, 0x9a, 0xd7, 0x79, 0x34,
    # 0xe3, 0xae and ends 0x7f, 0x32, 0xe5, 0xa8 (polynomial 0x4D).
    assert list(CRC_TABLE[:8]) == [0x00, 0x4D, 0x9A, 0xD7, 0x79, 0x34, 0xE3, 0xAE]
    assert list(CRC_TABLE[-4:]) == [0x7F, 0x32, 0xE5, 0xA8]


def _ld_packet(
    speed: int, start: int, points: list[tuple[int, int]], end: int, stamp: int
) -> bytes:
    body = struct.pack("<BBHH", 0x54, 0x2C, speed, start)
    for distance, intensity in points:
        body += struct.pack("<HB", distance, intensity)
    body += struct.pack("<HH", end, stamp)
    return body + bytes([crc8(body)])


def test_ld06_packets_spread_12_points_from_start_to_end_angle() -> None:
    points = [(1000 + 250 * i, 200) for i in range(12)]
    packet = _ld_packet(3600, 35950, points, 35950 + 1100 - 36000, 29999)  # 359.5 .. 10.5 deg
    assert len(packet) == 47
    parser = LdlidarParser()
    packets = parser.feed(packet)
    angles = [a for p in packets for a in p.angles_deg]
    assert angles == pytest.approx([(359.5 + i) % 360 for i in range(12)], abs=0.01)
    assert [d for p in packets for d in p.distances_mm] == [d for d, _ in points]
    assert packets[0].scan_hz == pytest.approx(10.0)  # 3600 degrees per second
    assert parser.timestamp_ms == 29999
    # the first packet has no turn before it; the next passing 0 starts one
    again = parser.feed(_ld_packet(3600, 35950, points, 1050, 12))
    assert [p.zero for p in again] == [False, True]
    assert again[1].angles_deg[0] == pytest.approx(0.5, abs=0.01)


def test_ld06_resynchronises_after_a_cut_and_a_corrupted_byte() -> None:
    good = _ld_packet(3600, 1000, [(500, 100)] * 12, 2100, 5)
    corrupted = bytearray(good)
    corrupted[20] ^= 0x01
    parser = LdlidarParser()
    packets = parser.feed(good[:30] + good + bytes(corrupted) + b"\x54\x2c\x54" + good)
    assert len(packets) == 2
    assert parser.stats.drops["bad_crc"] >= 1
    assert parser.stats.skipped_bytes > 0
