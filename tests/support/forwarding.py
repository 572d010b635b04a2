"""What the MAVLink forwarding tests share (tests/unit/vehicle_agents/forwarding/): the
(system, component) ids of the vehicle, the agent and the ground stations beside it, and
the vehicle's heartbeat."""

from __future__ import annotations

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from vehicle_agents.fcu.messages import MavMessage

VEHICLE = (1, 1)
AGENT = (254, 191)
QGC = (255, 190)
MAVPROXY = (255, 230)
OTHER_GCS = (250, 190)


def heartbeat(kind: int = mavlink2.MAV_TYPE_QUADROTOR) -> MavMessage:
    autopilot = (
        mavlink2.MAV_AUTOPILOT_INVALID
        if kind == mavlink2.MAV_TYPE_GCS
        else mavlink2.MAV_AUTOPILOT_ARDUPILOTMEGA
    )
    return mavlink2.MAVLink_heartbeat_message(kind, autopilot, 0, 0, 0, 3)
