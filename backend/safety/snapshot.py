"""What the rails know of a vehicle: the hub's last report of it, read so that anything
not known (None, NaN, or an autopilot's 0°N 0°E "no position yet") stays unknown and the
rules that need it fail closed."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Final, Protocol

from common.geodesy import GeoPoint
from protocol.messages import VehicleState

# Below this height a vehicle counts as on the ground for the launch rules.
LANDED_BELOW_M: Final = 0.5


@dataclass(frozen=True)
class VehicleSnapshot:
    """What the hub last heard from a vehicle; None (or NaN) means not known."""

    lat: float | None
    lon: float | None
    alt_rel: float | None
    home_lat: float | None
    home_lon: float | None
    battery_remaining_pct: float | None
    armed: bool
    landed: bool
    home_alt_msl: float | None = None


class ReportedVehicle(Protocol):
    """What the rules read of the fleet's record of a vehicle (``backend.fleet.registry``'s
    ``VehicleRecord``), declared here so that the rules never import the fleet."""

    @property
    def id(self) -> str: ...

    @property
    def autopilot(self) -> str: ...

    @property
    def vehicle_type(self) -> str: ...

    @property
    def state(self) -> VehicleState | None: ...


def snapshot_of(record: ReportedVehicle) -> VehicleSnapshot:
    state = record.state
    if state is None:
        return VehicleSnapshot(None, None, None, None, None, None, armed=False, landed=True)
    landed = not state.armed or (state.alt_rel is not None and state.alt_rel < LANDED_BELOW_M)
    return VehicleSnapshot(
        lat=state.lat,
        lon=state.lon,
        alt_rel=state.alt_rel,
        home_lat=state.home_lat,
        home_lon=state.home_lon,
        battery_remaining_pct=state.battery_remaining,
        armed=state.armed,
        landed=landed,
        home_alt_msl=state.home_alt_msl,
    )


def known(value: float | None) -> float | None:
    return value if value is not None and math.isfinite(value) else None


def _point(lat: float | None, lon: float | None) -> GeoPoint | None:
    lat, lon = known(lat), known(lon)
    if lat is None or lon is None or (lat, lon) == (0.0, 0.0):
        # 0°N 0°E is an autopilot's "no position yet" (ArduPilot before its EKF origin),
        # from an agent that passed it on: unknown, so the rules fail closed.
        return None
    return GeoPoint(lat, lon)


def position(vehicle: VehicleSnapshot) -> GeoPoint | None:
    return _point(vehicle.lat, vehicle.lon)


def home(vehicle: VehicleSnapshot) -> GeoPoint | None:
    return _point(vehicle.home_lat, vehicle.home_lon)


def altitude(vehicle: VehicleSnapshot) -> float | None:
    alt = known(vehicle.alt_rel)
    # A landed vehicle is on the ground; its altitude reading only adds barometer drift.
    return 0.0 if alt is None and vehicle.landed else alt
