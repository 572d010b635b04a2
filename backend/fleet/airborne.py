"""Whether a vehicle flies, from what its agent last reported, for the commands that
need it in the air (a formation's members take their slots from where they fly; a
grounded one switched to GUIDED only sits there, and the formation never forms).

The autopilot's own word is used (VehicleState.landed_state, from EXTENDED_SYS_STATE or
the agent's derivation where the autopilot has none), never the altitude: a field above
or below home misleads it. Anything not known is refused as unknown, never taken as
flying or as grounded.
"""

from __future__ import annotations

from protocol.messages import VehicleState


def not_airborne(vehicle_id: str, state: VehicleState | None) -> str | None:
    """Why ``vehicle_id`` cannot be taken as flying, or None when it flies."""
    if state is None:
        return f"{vehicle_id} has not reported its state"
    if not state.fcu_connected:
        return f"{vehicle_id}: its flight controller is not connected, its landed state is unknown"
    match state.landed_state:
        case None:
            return f"{vehicle_id}: its landed state is unknown"
        case "on_ground":
            return f"{vehicle_id} is on the ground: take off first"
        case "landing":
            return f"{vehicle_id} is landing"
        case "takeoff" | "in_air":
            pass
    if not state.armed:
        # reports itself in the air, disarmed: a contradiction, not a flying vehicle
        return f"{vehicle_id} is disarmed: take off first"
    return None
