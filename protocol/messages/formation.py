"""Hub -> agent: a formation slot to fly, the leader's state and scans relayed to each
follower, and the end of the formation."""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import Field, model_validator

from protocol.messages.base import MAX_UNIX_TIME, Message, VehicleId

FormationId = Annotated[str, Field(pattern=r"^[A-Za-z0-9_.-]{1,64}$", max_length=64)]
_OFFSET_M = 500.0
_LOCAL_M = 100_000.0  # a formation's route stays within 100 km of its first waypoint
_SPEED_MS = 100.0


class GraphEdge(Message):
    """A neighbour in a consensus follower's communication graph: its slot (the same
    axes as the follower's own) and the edge's weight."""

    vehicle_id: VehicleId
    x: float = Field(ge=-_OFFSET_M, le=_OFFSET_M)
    y: float = Field(ge=-_OFFSET_M, le=_OFFSET_M)
    up: float = Field(ge=-_OFFSET_M, le=_OFFSET_M)
    frame: Literal["heading", "ne"] = "heading"
    weight: float = Field(default=1.0, gt=0, le=10)


class FormationSlot(Message):
    """Fly this slot in a formation; sent again with a new offset when the shape or
    spacing changes in flight. Positions in the formation's messages are metres north,
    east and up (above home) on the tangent plane at ``origin``."""

    type: Literal["formation"] = "formation"
    formation_id: FormationId
    origin_lat: float = Field(ge=-90, le=90)
    origin_lon: float = Field(ge=-180, le=180)
    x: float = Field(ge=-_OFFSET_M, le=_OFFSET_M, description="forward (heading) or north")
    y: float = Field(ge=-_OFFSET_M, le=_OFFSET_M, description="right (heading) or east")
    up: float = Field(ge=-_OFFSET_M, le=_OFFSET_M, description="metres above the leader")
    frame: Literal["heading", "ne"] = "heading"
    min_separation_m: float = Field(gt=0, le=100)
    face_heading: bool = Field(
        default=False, description="turn to the leader's heading (a leader flying the route)"
    )
    controller: Literal["leader_follower", "consensus"] = Field(
        default="leader_follower",
        description="leader_follower: position targets around the predicted leader with "
        "its velocity as feed-forward; consensus: velocity targets from the leader's and "
        "the graph neighbours' states",
    )
    k_leader: float = Field(default=1.0, gt=0, le=100, description="consensus: the leader's weight")
    k_neighbour: float = Field(
        default=0.5, ge=0, le=100, description="consensus: each neighbour's weight"
    )
    graph: list[GraphEdge] = Field(
        default_factory=list, max_length=64, description="consensus: this follower's neighbours"
    )
    obstacle_clearance_m: float = Field(
        default=0.0,
        ge=0,
        le=50,
        description="hold short when the slot comes this close to a point of the leader's "
        "scans (0: not checked)",
    )


class FormationEnd(Message):
    """Leave the formation and hold."""

    type: Literal["formation_end"] = "formation_end"
    formation_id: FormationId
    reason: str = Field(default="", max_length=200)


class Neighbour(Message):
    """Another member's last report: for the separation check, and (with its velocity
    and time, to predict it as the leader is) for a consensus follower."""

    vehicle_id: VehicleId
    north: float = Field(ge=-_LOCAL_M, le=_LOCAL_M)
    east: float = Field(ge=-_LOCAL_M, le=_LOCAL_M)
    up: float = Field(ge=-_LOCAL_M, le=_LOCAL_M)
    vn: float = Field(default=0.0, ge=-_SPEED_MS, le=_SPEED_MS)
    ve: float = Field(default=0.0, ge=-_SPEED_MS, le=_SPEED_MS)
    vu: float = Field(default=0.0, ge=-_SPEED_MS, le=_SPEED_MS)
    time: float | None = Field(default=None, ge=0, le=MAX_UNIX_TIME)


class LeaderUpdate(Message):
    """The leader's state relayed to a follower (newest wins), with the other members'
    positions for the separation check. ``time`` is when the leader was there (Unix
    seconds): the follower predicts it forward over the link's delay."""

    type: Literal["leader"] = "leader"
    formation_id: FormationId
    time: float = Field(ge=0, le=MAX_UNIX_TIME)
    north: float = Field(ge=-_LOCAL_M, le=_LOCAL_M)
    east: float = Field(ge=-_LOCAL_M, le=_LOCAL_M)
    up: float = Field(ge=-_LOCAL_M, le=_LOCAL_M)
    vn: float = Field(ge=-_SPEED_MS, le=_SPEED_MS)
    ve: float = Field(ge=-_SPEED_MS, le=_SPEED_MS)
    vu: float = Field(ge=-_SPEED_MS, le=_SPEED_MS)
    heading_deg: float = Field(ge=0, le=360)
    neighbours: list[Neighbour] = Field(default_factory=list, max_length=64)


MAX_SCAN_POINTS = 1024


class LeaderScan(Message):
    """The returns of one of the leader's LIDAR scans, relayed to each follower in the
    formation's frame (metres north and east on its tangent plane), thinned to one per
    cell and at most `MAX_SCAN_POINTS`. A 2-D scan says nothing of height: a follower
    treats each point as an obstacle from the ground up. ``time`` is the scan's (Unix
    seconds), ``seq`` the leader's scan number."""

    type: Literal["leader_scan"] = "leader_scan"
    formation_id: FormationId
    time: float = Field(ge=0, le=MAX_UNIX_TIME)
    seq: int = Field(ge=0)
    north: list[float] = Field(max_length=MAX_SCAN_POINTS)
    east: list[float] = Field(max_length=MAX_SCAN_POINTS)

    @model_validator(mode="after")
    def _paired(self) -> LeaderScan:
        if len(self.north) != len(self.east):
            raise ValueError("north and east must list the same number of points")
        if any(abs(v) > _LOCAL_M for v in (*self.north, *self.east)):
            raise ValueError(f"points must lie within {_LOCAL_M:g} m of the origin")
        return self
