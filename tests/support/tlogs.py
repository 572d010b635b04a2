"""The .tlog files an agent writes, as a test reads them."""

from __future__ import annotations

import struct
import time

from pymavlink.dialects.v20 import ardupilotmega as mavlink2


def tlog_of(size: int) -> bytes:
    """About ``size`` bytes of a real .tlog: timestamped MAVLink 2 frames."""
    mav = mavlink2.MAVLink(None, srcSystem=1, srcComponent=1)
    records = bytearray()
    now = int(time.time() * 1e6)
    while len(records) < size:
        frame = mavlink2.MAVLink_attitude_message(len(records), 0.1, 0.2, 0.3, 0, 0, 0)
        records += struct.pack(">Q", now + len(records)) + frame.pack(mav)
    return bytes(records)
