"""A small synthetic flight for the export tests."""

from __future__ import annotations

import math

from backend.exports import ExportEvent, ExportFlight, ExportSample

T0 = 1_700_000_000.0
RATE_HZ = 10


def flight(autopilot: str = "ardupilot", vehicle_type: str = "multirotor") -> ExportFlight:
    return ExportFlight(
        id=7,
        vehicle_id="alpha-1",
        autopilot=autopilot,
        vehicle_type=vehicle_type,
        system_id=3,
        start_time=T0,
        end_time=T0 + 10.0,
    )


def sample(index: int, mode: str = "GUIDED", armed: bool = True) -> ExportSample:
    """Sample ``index`` at 10 Hz; the first three have no position yet."""
    has_position = index >= 3
    return ExportSample(
        time=T0 + index / RATE_HZ,
        lat=47.397742 + index * 1e-5 if has_position else None,
        lon=8.545594 - index * 2e-5 if has_position else None,
        alt_msl=488.25 + index * 0.5 if has_position else None,
        alt_rel=index * 0.5 if has_position else None,
        heading_deg=(index * 7.5) % 360 if has_position else None,
        groundspeed=2.5 if has_position else None,
        climb_rate=0.5,
        battery_voltage=16.2 - index * 0.001,
        battery_remaining=None if index == 0 else 90.0 - index * 0.1,
        mode=mode,
        armed=armed,
        gps_fix=3 if has_position else 1,
        satellites=None if index == 0 else 12,
    )


def samples(
    count: int = 60, modes: tuple[str, ...] = ("STABILIZE", "GUIDED", "LAND")
) -> list[ExportSample]:
    """``count`` samples cycling through ``modes`` and disarmed for the last five."""
    per_mode = math.ceil(count / len(modes))
    return [sample(i, modes[i // per_mode], armed=i < count - 5) for i in range(count)]


def events() -> list[ExportEvent]:
    return [
        ExportEvent(time=T0 + 4.04, kind="mode", severity=None, text="Mode GUIDED"),
        ExportEvent(time=T0 - 1.0, kind="statustext", severity=4, text="PreArm: before take-off"),
        ExportEvent(time=T0 + 0.1, kind="armed", severity=6, text="Armed"),
        ExportEvent(time=T0 + 99.0, kind="statustext", severity=2, text="x" * 80),
    ]
