"""The hub's one exception tree. The API edge turns these into HTTP status codes.

GcsError
├── VehicleNotFound        404  no vehicle with that id has ever connected
├── InvalidRequest         422  a value is out of range for this vehicle; names the field
├── VehicleOffline         409  the vehicle is known but its agent is not connected
└── CommandTimedOut        504  the agent or the flight controller did not answer in time
"""

from __future__ import annotations


class GcsError(Exception):
    status_code = 500

    def __init__(self, message: str) -> None:
        super().__init__(message)
        self.message = message


class VehicleNotFound(GcsError):
    status_code = 404

    def __init__(self, vehicle_id: str) -> None:
        super().__init__(f"unknown vehicle {vehicle_id!r}")
        self.vehicle_id = vehicle_id


class InvalidRequest(GcsError):
    status_code = 422

    def __init__(self, field: str, message: str) -> None:
        super().__init__(message)
        self.field = field


class VehicleOffline(GcsError):
    status_code = 409


class CommandTimedOut(GcsError):
    status_code = 504
