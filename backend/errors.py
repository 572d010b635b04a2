"""The hub's one exception tree. The API edge turns these into HTTP status codes.

GcsError
├── Unauthenticated        401  no credentials, or expired / revoked / wrong ones
├── Forbidden              403  authenticated, but the role or token does not allow it
├── NotFound               404  no such user, token, ...
│   └── VehicleNotFound         no vehicle with that id has ever connected
├── Conflict               409  e.g. a username that exists
├── VehicleRefused         409  the flight controller kept its value
├── InvalidRequest         422  a value is out of range for this vehicle; names the field
├── VehicleOffline         409  the vehicle is known but its agent is not connected
├── SafetyViolation        422  the command or mission breaks safety rails; lists every rule
├── RateLimited            429  too many attempts; carries Retry-After
└── CommandTimedOut        504  the agent or the flight controller did not answer in time
"""

from __future__ import annotations


class GcsError(Exception):
    status_code = 500
    # Set on a command's failure that the hub carrying it out (an agent on another hub)
    # has audited and logged already: the asking hub must not record it twice.
    recorded_elsewhere = False

    def __init__(self, message: str) -> None:
        super().__init__(message)
        self.message = message


class NotFound(GcsError):
    status_code = 404


class Conflict(GcsError):
    status_code = 409


class VehicleNotFound(NotFound):
    def __init__(self, vehicle_id: str) -> None:
        super().__init__(f"unknown vehicle {vehicle_id!r}")
        self.vehicle_id = vehicle_id


class InvalidRequest(GcsError):
    status_code = 422

    def __init__(self, field: str, message: str, location: str = "body") -> None:
        super().__init__(message)
        self.field = field
        self.location = location  # body, query or path, as in FastAPI's own 422s


class QuotaExceeded(GcsError):
    """A request that would store more than its owner's configured share (413)."""

    status_code = 413


class RequestTooLarge(GcsError):
    """A request whose content is over a size limit (413); the message names it."""

    status_code = 413


class VehicleOffline(GcsError):
    status_code = 409


class VehicleRefused(GcsError):
    """The flight controller answered, but not with what was asked (a parameter it kept)."""

    status_code = 409


class CommandTimedOut(GcsError):
    status_code = 504


class Unauthenticated(GcsError):
    status_code = 401


class Forbidden(GcsError):
    status_code = 403


class RateLimited(GcsError):
    status_code = 429

    def __init__(self, message: str, retry_after_s: float) -> None:
        super().__init__(message)
        self.retry_after_s = retry_after_s


class SafetyViolation(GcsError):
    """Carries the violated rules; the API lists them all."""

    status_code = 422

    def __init__(self, violations: list[dict[str, object]]) -> None:
        rules = ", ".join(str(v["rule"]) for v in violations)
        super().__init__(f"refused by safety rules: {rules}")
        self.violations = violations
