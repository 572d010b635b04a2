"""REST body of a formation mission. Unknown fields, NaN and infinities are rejected."""

from __future__ import annotations

from pydantic import BaseModel, ConfigDict, Field

from common.formation import Controller, OffsetFrame, Shape
from protocol.messages import Number, VehicleId

MAX_FOLLOWERS = 32
MAX_ROUTE_POINTS = 500


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", allow_inf_nan=False)


class RoutePoint(_Strict):
    lat: Number = Field(ge=-90, le=90)
    lon: Number = Field(ge=-180, le=180)
    alt_m: Number = Field(ge=0, le=10_000, description="The leader's altitude above home")


class OffsetModel(_Strict):
    x: Number = Field(ge=-500, le=500, description="Metres forward (heading) or north (ne)")
    y: Number = Field(ge=-500, le=500, description="Metres right (heading) or east (ne)")
    up: Number = Field(default=0.0, ge=-500, le=500, description="Metres above the leader")
    frame: OffsetFrame = OffsetFrame.HEADING


class FollowerModel(_Strict):
    vehicle_id: VehicleId
    offset: OffsetModel | None = Field(
        default=None, description="Its slot; null takes the next slot of the shape preset"
    )
    up: Number = Field(
        default=0.0, ge=-500, le=500, description="Metres above the leader in a preset slot"
    )
    neighbours: list[VehicleId] | None = Field(
        default=None,
        max_length=MAX_FOLLOWERS,
        description="Consensus: the followers it hears (its communication graph's edges, "
        "weight 1); null hears every other follower",
    )


class FormationRequest(_Strict):
    leader_id: VehicleId | None = Field(
        default=None, description="The leading vehicle; null for a virtual leader"
    )
    route: list[RoutePoint] = Field(min_length=2, max_length=MAX_ROUTE_POINTS)
    speed_ms: Number = Field(gt=0, le=30, description="The leader's speed along the route")
    pause_s: Number = Field(default=0.0, ge=0, le=3600, description="Pause at each waypoint")
    followers: list[FollowerModel] = Field(min_length=1, max_length=MAX_FOLLOWERS)
    shape: Shape = Shape.WEDGE
    spacing_m: Number = Field(default=3.0, gt=0, le=500)
    min_separation_m: Number = Field(
        default=2.0, gt=0, le=100, description="No two vehicles ever closer than this"
    )
    obstacle_clearance_m: Number = Field(
        default=2.0,
        ge=0,
        le=50,
        description="A follower whose slot comes this close (horizontally) to a point of "
        "the leader's LIDAR scans holds short of it; 0 turns the check off",
    )
    controller: Controller = Field(
        default=Controller.LEADER_FOLLOWER,
        description="leader_follower: each follower flies its slot around the leader; "
        "consensus: also agrees with its neighbours on where the leader is",
    )
    k_leader: Number = Field(default=1.0, gt=0, le=100, description="Consensus: leader weight")
    k_neighbour: Number = Field(
        default=0.5, ge=0, le=100, description="Consensus: weight of each neighbour"
    )


class ShapeChange(_Strict):
    """A new shape or spacing in flight: the followers glide to their new slots."""

    shape: Shape | None = None
    spacing_m: Number | None = Field(default=None, gt=0, le=500)
