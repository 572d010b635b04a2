"""What every builder of the simulated vehicle's MAVLink messages shares: the vehicle, the
wall-clock time at its sim time zero, its second GPS, and the stamps they make.

pymavlink is used only to construct message objects here; encoding happens per
connection in the transport. Field conventions follow ArduPilot's GCS_Common.cpp.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from simulator.vehicle import Vehicle

MavMessage = Any  # pymavlink message classes are generated and untyped

UINT16_MAX = 65535
INT16_MAX = 32767


@dataclass(frozen=True)
class SecondGps:
    """A second receiver (GPS2_RAW), e.g. an RTK rover beside the primary GPS. It reports
    the true position: at RTK accuracy the simulated noise is negligible."""

    fix_type: int = mavlink2.GPS_FIX_TYPE_RTK_FIXED
    satellites: int = 18


class MessageContext:
    """The vehicle a builder describes, and the clocks its messages are stamped with."""

    def __init__(self, copter: Vehicle, boot_epoch_s: float, gps2: SecondGps | None = None) -> None:
        self.copter = copter
        self.boot_epoch_s = boot_epoch_s  # wall-clock time at sim time zero, for GPS time
        self.gps2 = gps2  # None: not fitted (or unplugged), GPS2_RAW is not sent

    @property
    def _time_boot_ms(self) -> int:
        return int(self.copter.time_s * 1000.0) & 0xFFFFFFFF

    @property
    def _time_usec(self) -> int:
        return int((self.boot_epoch_s + self.copter.time_s) * 1e6)
