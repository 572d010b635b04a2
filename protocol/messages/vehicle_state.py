"""A vehicle's state as its agent reports it, and where each value is physically possible."""

from __future__ import annotations

from typing import Literal

from pydantic import Field

from protocol.messages.base import MAX_NAME_CHARS, Message

# MAV_LANDED_STATE without its UNDEFINED (that is null): in_air, takeoff and landing are
# all airborne.
LandedState = Literal["on_ground", "takeoff", "in_air", "landing"]


class VehicleState(Message):
    """One telemetry snapshot, assembled by the agent from the latest MAVLink messages.
    The hub refuses a snapshot holding a physically impossible value (STATE_BOUNDS:
    latitude beyond ±90, an altitude of 1e308 ...): not stored, not shown, counted."""

    fcu_connected: bool = True
    mode: str = Field(default="UNKNOWN", max_length=MAX_NAME_CHARS)
    armed: bool = False
    system_status: str = Field(default="UNKNOWN", max_length=MAX_NAME_CHARS)
    landed_state: LandedState | None = Field(
        default=None,
        description="Whether it flies: on_ground, or airborne (takeoff, in_air, landing). "
        "Use this, not the altitude (a field above or below home misleads it). Null until "
        "known.",
    )
    landed_state_source: Literal["autopilot", "derived"] | None = Field(
        default=None,
        description="autopilot: EXTENDED_SYS_STATE.landed_state (ArduCopter, ArduPlane, "
        "PX4); derived: the agent's guess from armed, the altitude above home and the climb "
        "rate, where the autopilot does not say (ArduPilot Rover, old firmware): never "
        "takeoff or landing, and a ground vehicle is always on_ground",
    )
    lat: float | None = None
    lon: float | None = None
    alt_msl: float | None = Field(default=None, description="Metres above mean sea level.")
    alt_rel: float | None = Field(default=None, description="Metres above home.")
    heading_deg: float | None = None
    groundspeed: float | None = Field(default=None, description="m/s")
    climb_rate: float | None = Field(default=None, description="m/s, up is positive")
    vn: float | None = Field(default=None, description="m/s north (GLOBAL_POSITION_INT.vx)")
    ve: float | None = Field(default=None, description="m/s east (GLOBAL_POSITION_INT.vy)")
    roll_deg: float | None = None
    pitch_deg: float | None = None
    battery_voltage: float | None = None
    battery_current: float | None = Field(default=None, description="A")
    battery_remaining: float | None = Field(default=None, description="percent")
    gps_fix: int = Field(
        default=0, ge=0, le=255, description="GPS_FIX_TYPE: 0-1 none, 2 2D, 3 3D, 4+ DGPS/RTK"
    )
    satellites: int | None = Field(default=None, ge=0, le=255)
    ready_to_fly: bool | None = Field(
        default=None,
        description="the autopilot's pre-arm checks and estimator allow a take-off "
        "(EKF_STATUS_REPORT, SYS_STATUS, PreArm texts); null until it has said",
    )
    not_ready_reason: str | None = Field(
        default=None, max_length=500, description="why it is not ready, when it is not"
    )
    home_lat: float | None = None
    home_lon: float | None = None
    home_alt_msl: float | None = None
    mission_current: int | None = Field(
        default=None, description="the mission item being flown (MISSION_CURRENT)"
    )
    mission_total: int | None = None
    position_source: str | None = Field(
        default=None,
        max_length=MAX_NAME_CHARS,
        description="the position source in use, e.g. GPS_RAW_INT or GPS2_RAW (RTK)",
    )
    fcu_receive_errors: int = Field(
        default=0, ge=0, description="garbage bytes and bad frames skipped on the FCU link"
    )
    outbox_pending: int = Field(default=0, ge=0, description="frames not yet stored by the hub")
    outbox_dropped: int = Field(
        default=0, ge=0, description="frames the agent dropped because its outbox was full"
    )


# Where a reported value is physically possible, inclusive, per VehicleState field. An
# agent's sample with a value outside (a latitude of 91, an altitude of 1e308: a broken
# sensor, a decoding bug, a hostile peer) is refused whole by the hub, counted, and never
# stored or shown; the agent's link goes on. Not field constraints of VehicleState: the
# agent builds one from whatever the flight controller says, and must not fail doing so.
STATE_BOUNDS: dict[str, tuple[float, float]] = {
    "lat": (-90.0, 90.0),
    "lon": (-180.0, 180.0),
    "home_lat": (-90.0, 90.0),
    "home_lon": (-180.0, 180.0),
    # metres above mean sea level: the Dead Sea shore is at -430, 100 km is space
    "alt_msl": (-1_000.0, 100_000.0),
    "home_alt_msl": (-1_000.0, 100_000.0),
    # metres above home: a vehicle homed on a summit may fly far below it
    "alt_rel": (-10_000.0, 100_000.0),
    "heading_deg": (-360.0, 360.0),
    "roll_deg": (-180.0, 180.0),
    "pitch_deg": (-180.0, 180.0),
    # m/s: 500 is beyond any vehicle this station flies (about Mach 1.5)
    "groundspeed": (0.0, 500.0),
    "climb_rate": (-500.0, 500.0),
    "vn": (-500.0, 500.0),
    "ve": (-500.0, 500.0),
    "battery_voltage": (0.0, 1_000.0),  # V
    "battery_current": (-1_000.0, 1_000.0),  # A; negative while charging
    "battery_remaining": (0.0, 100.0),  # percent
}


def state_out_of_range(state: VehicleState) -> list[tuple[str, str]]:
    """Each field of ``state`` outside STATE_BOUNDS, with the problem said ("lat 91 is
    outside -90..90"); empty for a possible state. None is unknown, not out of range;
    non-finite numbers never get this far (the frame's parse refuses them)."""
    problems = []
    for name, (low, high) in STATE_BOUNDS.items():
        value = getattr(state, name)
        if value is not None and not low <= value <= high:
            problems.append((name, f"{name} {value:g} is outside {low:g}..{high:g}"))
    return problems
