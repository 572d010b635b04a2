"""Whether the vehicle has a position, and which GNSS receiver it comes from.

A position is GLOBAL_POSITION_INT, the autopilot's estimate, once it has one. ArduPilot
streams the message from boot, filled with zeros until its EKF has an origin; PX4 sends
it only while its global position is valid, so its sign of "none" is silence while the
heartbeats go on. Either way the agent reports no position rather than 0°N 0°E.

Which receiver: when the vehicle has more than one.
ArduPilot and PX4 report their first receiver in GPS_RAW_INT and the second in
GPS2_RAW. The best source present is the one with the better fix (RTK fixed > RTK float
> PPP > DGPS > 3D > 2D > none), then the one seeing more satellites, then the first
declared. A receiver whose message has not arrived within the freshness window is gone
(unplugged, disabled, or its stream stopped) and takes no part.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from vehicle_agents.fcu.messages import MavMessage

SATELLITES_UNKNOWN = 255

# GPS_FIX_TYPE, best last. STATIC is a base station's surveyed fix, as good as a 3D fix
# on a vehicle; PPP is decimetre-level, between DGPS and RTK. Unknown values rank as none.
FIX_RANK: Mapping[int, int] = {
    mavlink2.GPS_FIX_TYPE_NO_GPS: 0,
    mavlink2.GPS_FIX_TYPE_NO_FIX: 0,
    mavlink2.GPS_FIX_TYPE_2D_FIX: 1,
    mavlink2.GPS_FIX_TYPE_3D_FIX: 2,
    mavlink2.GPS_FIX_TYPE_STATIC: 2,
    mavlink2.GPS_FIX_TYPE_DGPS: 3,
    mavlink2.GPS_FIX_TYPE_PPP: 4,
    mavlink2.GPS_FIX_TYPE_RTK_FLOAT: 5,
    mavlink2.GPS_FIX_TYPE_RTK_FIXED: 6,
}


@dataclass(frozen=True)
class PositionTimeouts:
    # ArduPilot streams GPS_RAW_INT at 2-5 Hz; a receiver silent this long is gone.
    stale_after_s: float = 3.0
    # GLOBAL_POSITION_INT this much older than the latest heartbeat: the autopilot has
    # stopped estimating (PX4). Measured against the heartbeat, so a link that is down
    # altogether keeps its last known position (shown with fcu_connected false).
    position_lost_after_s: float = 3.0


DEFAULT_TIMEOUTS = PositionTimeouts()


@dataclass(frozen=True)
class PositionSource:
    """A message that reports one receiver's fix, declared as data."""

    message: str  # also the name reported in VehicleState.position_source
    fix_field: str = "fix_type"
    satellites_field: str = "satellites_visible"


# In order of preference when two are equally good: the autopilot's first receiver first.
SOURCES: tuple[PositionSource, ...] = (
    PositionSource("GPS_RAW_INT"),
    PositionSource("GPS2_RAW"),
)


@dataclass(frozen=True)
class PositionFix:
    source: str
    fix_type: int
    satellites: int | None

    @property
    def rank(self) -> int:
        return FIX_RANK.get(self.fix_type, 0)


def global_position(
    latest: Mapping[str, MavMessage],
    received_at: Mapping[str, float] | None,
    now: float,
    timeouts: PositionTimeouts = DEFAULT_TIMEOUTS,
) -> MavMessage | None:
    """The GLOBAL_POSITION_INT to report, or None while the autopilot has no position."""
    position = latest.get("GLOBAL_POSITION_INT")
    if position is None or (position.lat == 0 and position.lon == 0):
        # 0/0 is ArduPilot's "no origin yet", never a drone on Null Island (open sea)
        return None
    if received_at is not None:
        arrived = received_at.get("GLOBAL_POSITION_INT", now)
        heartbeat = received_at.get("HEARTBEAT", arrived)
        if heartbeat - arrived > timeouts.position_lost_after_s:
            return None
    return position


def candidates(
    latest: Mapping[str, MavMessage],
    received_at: Mapping[str, float] | None,
    now: float,
    timeouts: PositionTimeouts = DEFAULT_TIMEOUTS,
    sources: tuple[PositionSource, ...] = SOURCES,
) -> list[PositionFix]:
    """The fresh sources, in declaration order. Without arrival times, all count as fresh."""
    found: list[PositionFix] = []
    for source in sources:
        message = latest.get(source.message)
        if message is None:
            continue
        if received_at is not None:
            arrived = received_at.get(source.message)
            if arrived is None or now - arrived > timeouts.stale_after_s:
                continue
        satellites = int(getattr(message, source.satellites_field))
        found.append(
            PositionFix(
                source.message,
                int(getattr(message, source.fix_field)),
                None if satellites == SATELLITES_UNKNOWN else satellites,
            )
        )
    return found


def best(fixes: list[PositionFix]) -> PositionFix | None:
    """The best fix, then the most satellites; ties go to the earlier source."""
    chosen: PositionFix | None = None
    for fix in fixes:
        if chosen is None or _key(fix) > _key(chosen):
            chosen = fix
    return chosen


def choose(
    latest: Mapping[str, MavMessage],
    received_at: Mapping[str, float] | None,
    now: float,
    timeouts: PositionTimeouts = DEFAULT_TIMEOUTS,
) -> PositionFix | None:
    """The position source to report, or None when no receiver is heard from."""
    return best(candidates(latest, received_at, now, timeouts))


def _key(fix: PositionFix) -> tuple[int, int]:
    return fix.rank, fix.satellites or 0
