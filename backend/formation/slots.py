"""What each member of a formation is told of its place: its slot, the formation's
origin and separation, the controller and its gains, and whom it hears (the consensus
graph, each neighbour with its own slot)."""

from __future__ import annotations

from backend.formation.active import ActiveFormation
from common.formation import Offset
from protocol.messages import FormationSlot, GraphEdge


def slot_messages(formation: ActiveFormation) -> dict[str, FormationSlot]:
    """Each member's FormationSlot; a leader vehicle's is a zero offset, facing along
    the route."""
    plan = formation.plan
    origin = plan.frame.origin
    slots = dict(formation.offsets)
    if plan.leader_id:
        slots[plan.leader_id] = Offset(0.0, 0.0, 0.0)
    messages = {}
    for vehicle_id, offset in slots.items():
        graph = [
            GraphEdge(
                vehicle_id=heard,
                x=slots[heard].x,
                y=slots[heard].y,
                up=slots[heard].up,
                frame=slots[heard].frame.value,
                weight=weight,
            )
            for heard, weight in plan.graph.get(vehicle_id, {}).items()
        ]
        messages[vehicle_id] = FormationSlot(
            formation_id=formation.id,
            origin_lat=origin.lat,
            origin_lon=origin.lon,
            x=offset.x,
            y=offset.y,
            up=offset.up,
            frame=offset.frame.value,
            min_separation_m=plan.min_separation_m,
            obstacle_clearance_m=formation.request.obstacle_clearance_m,
            face_heading=vehicle_id == plan.leader_id,
            controller=plan.controller.value,
            k_leader=plan.gains.k_leader,
            k_neighbour=plan.gains.k_neighbour,
            graph=graph,
        )
    return messages
