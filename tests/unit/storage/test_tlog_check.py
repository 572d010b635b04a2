"""The hub's .tlog content check: what QGroundControl, MAVProxy and our recorder write
passes (MAVLink 1 and 2, signed frames, unknown messages, a torn last record); what is
not timestamped MAVLink is refused at its first bad record."""

from __future__ import annotations

import re
import struct

import pytest
from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from backend.storage.tlog_check import InvalidTlog, TlogChecker

STAMP = struct.pack(">Q", 1_700_000_000_000_000)


def _frames(*, v1: bool = False, signed: bool = False) -> bytes:
    mav = mavlink2.MAVLink(None, srcSystem=1, srcComponent=1)
    if signed:
        mav.signing.secret_key = bytes(range(32))
        mav.signing.sign_outgoing = True
    heartbeat = mavlink2.MAVLink_heartbeat_message(2, 3, 81, 4, 4, 3)
    attitude = mavlink2.MAVLink_attitude_message(1, 0.1, 0.2, 0.3, 0, 0, 0)
    return b"".join(STAMP + m.pack(mav, force_mavlink1=v1) for m in (heartbeat, attitude))


def _check(data: bytes, chunk: int = 7) -> int:
    checker = TlogChecker()
    for at in range(0, len(data), chunk):  # split anywhere, as a stream arrives
        checker.feed(data[at : at + chunk])
    return checker.finish()


@pytest.mark.parametrize(
    "data",
    [_frames(), _frames(v1=True), _frames(signed=True), _frames() + _frames()[:20]],
    ids=["mavlink2", "mavlink1", "signed", "torn last record"],
)
def test_real_tlogs_pass(data: bytes) -> None:
    assert _check(data) >= 2


def test_a_message_this_dialect_does_not_know_passes_on_its_shape() -> None:
    unknown = bytes([0xFD, 1, 0, 0, 0, 1, 1]) + (60_000).to_bytes(3, "little") + b"\x00" * 3
    assert _check(STAMP + unknown + _frames()) == 3


@pytest.mark.parametrize(
    ("data", "reason"),
    [
        (bytes(100_000), "0x00 is not a MAVLink magic (at byte 8)"),
        (b"", "no complete MAVLink frame"),
        (_frames()[:-1] + b"\x00" + _frames(), "bad CRC for ATTITUDE"),
        (STAMP + bytes([0xFD, 0, 0x80]) + bytes(20), "unknown incompat_flags 0x80"),
        (b"GIF89a" + bytes(1000), "is not a MAVLink magic"),
    ],
    ids=["zeros", "empty", "bad crc", "bad flags", "another format"],
)
def test_what_is_not_a_tlog_is_refused_saying_where(data: bytes, reason: str) -> None:
    with pytest.raises(InvalidTlog, match=re.escape(reason)):
        _check(data)
