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


def flies(state: VehicleState) -> bool | None:
    """True while ``state`` says the vehicle flies (as ``not_airborne`` judges it), False
    while it is on the ground (landed, or disarmed), None when it cannot be told (no
    flight controller, no landed state yet): a take-off clock keeps running through that."""
    if not state.fcu_connected:
        return None
    if state.landed_state in ("takeoff", "in_air", "landing"):
        return state.armed or None  # airborne and disarmed contradicts itself: unknown
    if state.landed_state == "on_ground" or not state.armed:
        return False
    return None


class TakeoffClock:
    """When a vehicle took off, from its states in order: set by the first flying sample
    after a grounded one, cleared on the ground. A vehicle first seen already flying has
    no known take-off (None), never the time the hub first heard of it."""

    __slots__ = ("_seen_grounded", "airborne_since")

    def __init__(self) -> None:
        self.airborne_since: float | None = None
        self._seen_grounded = False

    def observe(self, state: VehicleState, time: float) -> None:
        match flies(state):
            case False:
                self.airborne_since = None
                self._seen_grounded = True
            case True if self.airborne_since is None and self._seen_grounded:
                self.airborne_since = time
                self._seen_grounded = False
            case _:
                pass
