"""The binary scan frame (protocol/scans.py): size, round trip, and what it refuses."""

from __future__ import annotations

import math
from array import array

import pytest

from protocol.scans import (
    FLAG_REPLAYED,
    HEADER_BYTES,
    MAX_SCAN_BYTES,
    ScanFrame,
    ScanFrameError,
    decode_scan,
    encode_scan,
    quantise,
    with_flags,
)
from tests.support.scans import _frame


def test_a_720_beam_scan_fits_in_2_kb_and_round_trips() -> None:
    frame = _frame()
    data = encode_scan(frame)
    assert len(data) == HEADER_BYTES + 1440
    assert len(data) <= 2048
    back = decode_scan(data)
    assert back.ranges == frame.ranges
    assert back.seq == 41
    assert back.sensor_time_us == 123_456_789
    assert back.utc_time == frame.utc_time
    assert back.pose_start.lat == frame.pose_start.lat  # f64: millimetres survive
    assert back.pose_end.yaw == pytest.approx(1.6, abs=1e-6)
    assert back.mount.yaw == pytest.approx(math.pi, abs=1e-6)
    assert not back.replayed
    assert decode_scan(with_flags(data, FLAG_REPLAYED)).replayed


def test_quantising_cleans_what_is_no_range() -> None:
    ranges, cleaned = quantise([math.nan, math.inf, -1.0, 0.0, 12.5, 0.0004, 11.9994], 0.001, 12.0)
    assert list(ranges) == [0, 0, 0, 0, 0, 1, 11999]
    assert cleaned == 4  # NaN, infinity, negative, beyond the maximum (0 is "no return")


@pytest.mark.parametrize(
    ("mangle", "rule"),
    [
        (lambda d: d[:-2], "beams: the header says 720 beams, the frame holds 719"),
        (lambda d: d + b"\0\0", "beams: the header says 720 beams"),
        (lambda d: b"XSCN" + d[4:], "magic"),
        (lambda d: d[:4] + b"\x09" + d[5:], "version: 9"),
        (lambda d: d[:10], "shorter than"),
        (lambda d: d + bytes(MAX_SCAN_BYTES), "over the limit"),
        # utc_time (offset 24) as NaN
        (lambda d: d[:24] + b"\0\0\0\0\0\0\xf8\x7f" + d[32:], "utc_time: must be a finite"),
    ],
)
def test_bad_frames_are_refused_naming_the_field(mangle: object, rule: str) -> None:
    data = encode_scan(_frame())
    with pytest.raises(ScanFrameError, match=rule):
        decode_scan(mangle(data))  # type: ignore[operator]


def test_the_encoder_refuses_what_the_decoder_would() -> None:
    frame = _frame()
    bad = ScanFrame(**{**{f: getattr(frame, f) for f in frame.__slots__}, "duration_s": 0.0})
    with pytest.raises(ScanFrameError, match="duration_s"):
        encode_scan(bad)
    with pytest.raises(ScanFrameError, match="beams"):
        encode_scan(
            ScanFrame(**{**{f: getattr(frame, f) for f in frame.__slots__}, "ranges": array("H")})
        )


def test_the_layout_is_exported_with_the_protocols_schema() -> None:
    from protocol.messages import json_schema

    layout = json_schema()["scan_frame"]
    fields = {f["name"]: f for f in layout["fields"]}
    assert layout["header_bytes"] == HEADER_BYTES
    assert fields["ranges"]["offset"] == HEADER_BYTES  # the header's fields add up
    data = encode_scan(_frame())
    seq = fields["seq"]["offset"]
    assert int.from_bytes(data[seq : seq + 8], "little") == 41
    beams = fields["beams"]["offset"]
    assert int.from_bytes(data[beams : beams + 2], "little") == 720


def test_the_dashboards_decoder_reads_the_exported_layout() -> None:
    import re
    from pathlib import Path

    from protocol.scans import scan_frame_schema

    layout = scan_frame_schema()
    source = (Path(__file__).parents[3] / "frontend/src/scans/scanFrame.ts").read_text()
    assert re.search(rf"const HEADER_BYTES = {layout['header_bytes']};", source)
    assert f'const SCAN_MAGIC = "{layout["magic"]}";' in source
    assert f'const CLIENT_MAGIC = "{layout["to_subscribers"]["magic"]}";' in source  # type: ignore[index]
