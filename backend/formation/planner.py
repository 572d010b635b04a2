"""A formation request checked and turned into the plan the followers fly.

Each refusal names its reason: two slots within the minimum separation, a follower that
is also the leader or listed twice, a vehicle already in another formation, a follower
not ready to fly, a speed above the vehicles' limit, and the leader's route (with every
slot around it) against the rails: geofence, altitudes, distance from home, battery.
"""

from __future__ import annotations

from collections.abc import Collection, Mapping
from dataclasses import dataclass, field

from backend.errors import InvalidRequest
from backend.formation.route import LeaderRoute
from backend.formation.schemas import FormationRequest
from backend.safety.mission_rails import evaluate_plan
from backend.safety.mission_waypoints import Waypoint
from backend.safety.rails import SafetyRails
from backend.safety.snapshot import VehicleSnapshot
from backend.safety.violations import Violation
from common.formation import (
    ConsensusGains,
    Controller,
    Offset,
    OffsetFrame,
    Shape,
    closest_pair,
    shape_offsets,
)
from common.geodesy import LocalFrame

LEADER = "leader"


class FormationRefused(InvalidRequest):
    """A formation that cannot fly as asked; ``violations`` lists rail breaches by member."""

    def __init__(
        self, field: str, message: str, violations: Mapping[str, list[Violation]] | None = None
    ) -> None:
        super().__init__(field, message)
        self.violations = dict(violations or {})


@dataclass(frozen=True)
class FormationPlan:
    leader_id: str | None
    frame: LocalFrame  # the route's local frame, at its first waypoint
    route: LeaderRoute
    offsets: dict[str, Offset]  # per follower
    min_separation_m: float
    controller: Controller = Controller.LEADER_FOLLOWER
    gains: ConsensusGains = field(default_factory=ConsensusGains)
    graph: dict[str, dict[str, float]] = field(default_factory=dict)  # follower: {heard: a_ij}

    def slot_points(self, heading_rad: float) -> dict[str, tuple[float, float, float]]:
        """Every member's place relative to the leader (the leader at the origin)."""
        out = {LEADER: (0.0, 0.0, 0.0)}
        out |= {v: o.north_east_up(heading_rad) for v, o in self.offsets.items()}
        return out


def follower_offsets(
    request: FormationRequest, shape: Shape | None = None, spacing_m: float | None = None
) -> dict[str, Offset]:
    """Each follower's slot: its own offset where given, else the next slot of the preset."""
    preset = shape_offsets(
        shape or request.shape,
        len(request.followers),
        spacing_m or request.spacing_m,
        [f.up for f in request.followers],
    )
    out: dict[str, Offset] = {}
    for follower, slot in zip(request.followers, preset, strict=True):
        o = follower.offset
        out[follower.vehicle_id] = Offset(o.x, o.y, o.up, o.frame) if o else slot
    return out


def check_separation(offsets: Mapping[str, Offset], min_separation_m: float) -> None:
    """Refuse slots (the leader's among them) closer than the minimum separation.
    Heading-frame slots keep their distances as the leader turns; north-east ones do not
    turn, so a mix is checked at every heading, a degree apart."""
    mixed = len({o.frame for o in offsets.values()}) > 1
    headings = [i * 0.017453292519943295 for i in range(360)] if mixed else [0.0]
    names = [LEADER, *offsets]
    for heading in headings:
        points = [(0.0, 0.0, 0.0)] + [o.north_east_up(heading) for o in offsets.values()]
        pair = closest_pair(points)
        if pair is not None and pair[0] < min_separation_m:
            d, i, j = pair
            raise FormationRefused(
                "followers",
                f"{names[i]} and {names[j]} would be {d:.2f} m apart; the minimum "
                f"separation is {min_separation_m:g} m",
            )


def plan_formation(
    request: FormationRequest,
    *,
    rails: SafetyRails,
    vehicles: Mapping[str, VehicleSnapshot],
    not_ready: Mapping[str, str] | None = None,
    not_airborne: Mapping[str, str] | None = None,
    busy: Collection[str] = (),
    max_speed_ms: float = 5.0,
) -> FormationPlan:
    """Check ``request`` and return its plan, or raise FormationRefused with the reason.

    ``vehicles`` is the hub's last report of each member; ``not_ready`` the reason each
    member that is not ready to fly gave; ``not_airborne`` why each member that is not
    known to fly is not (all are named in one refusal); ``busy`` the vehicles in another formation;
    ``max_speed_ms`` the slowest member's speed limit (WPNAV_SPEED or MPC_XY_VEL_MAX)."""
    followers = [f.vehicle_id for f in request.followers]
    if request.leader_id is not None and request.leader_id in followers:
        raise FormationRefused("followers", f"{request.leader_id} cannot lead and follow")
    if len(set(followers)) != len(followers):
        twice = next(v for v in followers if followers.count(v) > 1)
        raise FormationRefused("followers", f"{twice} is listed as a follower twice")
    members = followers + ([request.leader_id] if request.leader_id else [])
    for vehicle in members:
        if vehicle in busy:
            raise FormationRefused("followers", f"{vehicle} is already in another formation")
        if vehicle not in vehicles:
            raise FormationRefused("followers", f"{vehicle} has not reported its state")
        reason = (not_ready or {}).get(vehicle)
        if reason is not None:
            raise FormationRefused("followers", f"{vehicle} is not ready to fly: {reason}")
    # Members join from where they fly; one on the ground would sit in GUIDED and the
    # formation never form. Refused before any member is told anything.
    grounded = [reason for v in members if (reason := (not_airborne or {}).get(v))]
    if grounded:
        raise FormationRefused("followers", "; ".join(grounded))
    # The followers fly faster than the leader on the outside of its turns and while
    # they close on their slots; the leader's speed itself must be within every limit.
    if request.speed_ms > max_speed_ms:
        raise FormationRefused(
            "speed_ms",
            f"{request.speed_ms:g} m/s is above the vehicles' limit of {max_speed_ms:g} m/s",
        )
    offsets = follower_offsets(request)
    check_separation(offsets, request.min_separation_m)
    graph = communication_graph(request)

    first = request.route[0]
    frame = LocalFrame(first.lat, first.lon)
    points = []
    for p in request.route:
        east, north = frame.to_local(p.lat, p.lon)
        points.append((north, east, p.alt_m))
    route = LeaderRoute(points, request.speed_ms, request.pause_s)

    violations: dict[str, list[Violation]] = {}
    for vehicle in members:
        offset = offsets.get(vehicle, Offset(0.0, 0.0, 0.0, OffsetFrame.NORTH_EAST))
        checked = evaluate_plan(rails, vehicles[vehicle], _slot_waypoints(route, frame, offset))
        if checked.violations:
            violations[vehicle] = list(checked.violations)
    if violations:
        first_vehicle, found = next(iter(violations.items()))
        raise FormationRefused(
            "route",
            f"{first_vehicle}'s slot along the route: {found[0].message}",
            violations,
        )
    return FormationPlan(
        request.leader_id,
        frame,
        route,
        offsets,
        request.min_separation_m,
        request.controller,
        ConsensusGains(request.k_leader, request.k_neighbour),
        graph,
    )


def communication_graph(request: FormationRequest) -> dict[str, dict[str, float]]:
    """Who each consensus follower hears (weight 1): its listed neighbours, else every
    other follower. The leader is heard by all, so any graph converges; a neighbour that
    is not a follower of this formation, or the follower itself, is refused."""
    if request.controller is not Controller.CONSENSUS:
        return {}
    followers = [f.vehicle_id for f in request.followers]
    graph: dict[str, dict[str, float]] = {}
    for follower in request.followers:
        heard = follower.neighbours
        if heard is None:
            heard = [v for v in followers if v != follower.vehicle_id]
        for other in heard:
            if other == follower.vehicle_id:
                raise FormationRefused("followers", f"{other} cannot be its own neighbour")
            if other not in followers:
                raise FormationRefused(
                    "followers",
                    f"{follower.vehicle_id}'s neighbour {other} is not a follower of this "
                    "formation",
                )
        graph[follower.vehicle_id] = dict.fromkeys(heard, 1.0)
    return graph


def _slot_waypoints(route: LeaderRoute, frame: LocalFrame, offset: Offset) -> list[Waypoint]:
    """Where a slot goes along the route: at each waypoint, at the heading of the leg
    arriving and of the leg leaving (the slot swings between them during the pause)."""
    out: list[Waypoint] = []
    for i, leg in enumerate(route.legs):
        for point in (leg.start, leg.end):
            dn, de, du = offset.north_east_up(leg.heading_rad)
            lat, lon = frame.to_geo(point[1] + de, point[0] + dn)
            out.append(Waypoint(lat, lon, point[2] + du, i + 1))
    return out
