"""Hub <-> clients, the LIDAR's: subscribing to a vehicle's scans (binary frames,
`protocol.scans`) and to the site's point map and obstacles, and the layers sent."""

from __future__ import annotations

from typing import Literal, TypeAlias

from pydantic import BaseModel, Field

from protocol.messages.base import Message, VehicleId


class SubscribeScans(Message):
    """Send me this vehicle's scans (binary frames, protocol/scans.py), newest only."""

    type: Literal["subscribe_scans"] = "subscribe_scans"
    vehicle_id: VehicleId


class UnsubscribeScans(Message):
    type: Literal["unsubscribe_scans"] = "unsubscribe_scans"
    vehicle_id: VehicleId


MAX_SCAN_SUBSCRIPTIONS = 64


class ScanSubscriptions(Message):
    """The vehicles whose scans this feed now receives (the answer to a (un)subscribe)."""

    type: Literal["scan_subscriptions"] = "scan_subscriptions"
    vehicles: list[VehicleId] = Field(max_length=MAX_SCAN_SUBSCRIPTIONS)


MapLayer: TypeAlias = Literal["points", "obstacles"]
MAX_MAP_POINTS = 500_000  # the most the REST point map gives at once
MAX_MAP_POINTS_SENT = 20_000  # the newest voxels of a point_map message
MAX_OBSTACLES_SENT = 1_000


class SubscribeMap(Message):
    """Send me the site's map as it changes: ``points`` (the voxel point map, its newest
    voxels, at most every few seconds) and ``obstacles`` (the clusters found in it, when
    the set changes). The current state comes at once; a slow reader gets the newest."""

    type: Literal["subscribe_map"] = "subscribe_map"
    layers: list[MapLayer] = Field(min_length=1, max_length=2)


class UnsubscribeMap(Message):
    type: Literal["unsubscribe_map"] = "unsubscribe_map"
    layers: list[MapLayer] = Field(min_length=1, max_length=2)


class MapSubscriptions(Message):
    """The map layers this feed now receives (the answer to a (un)subscribe)."""

    type: Literal["map_subscriptions"] = "map_subscriptions"
    layers: list[MapLayer] = Field(max_length=2)


class SiteOrigin(BaseModel):
    """The origin of the site's east/north/up metres (the scans' and the point map's)."""

    lat: float
    lon: float
    alt_msl: float


class Obstacle(BaseModel):
    """A cluster of the point map, above the ground: its extent in site east/north/up
    metres; it keeps its id while it is seen."""

    id: int
    east_min: float
    east_max: float
    north_min: float
    north_max: float
    up_min: float
    up_max: float
    voxels: int
    outline: list[tuple[float, float]] = Field(
        max_length=4, description="the extent's corners as latitude, longitude (degrees)"
    )


class PointMapView(BaseModel):
    site: SiteOrigin | None
    voxel_m: float
    voxels: int = Field(description="voxels in the map (``points`` may hold fewer)")
    evicted: int = Field(description="voxels dropped so far to keep the map in its bound")
    points: list[tuple[float, float, float]] = Field(
        max_length=MAX_MAP_POINTS,
        description="voxel centres, east/north/up metres from the site origin, newest first",
    )


class PointMapUpdate(Message):
    type: Literal["point_map"] = "point_map"
    map: PointMapView


class ObstaclesUpdate(Message):
    type: Literal["obstacles"] = "obstacles"
    site: SiteOrigin | None
    obstacles: list[Obstacle] = Field(max_length=MAX_OBSTACLES_SENT)
