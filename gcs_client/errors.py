"""The client's one exception tree: catch ``HubError`` for all of them.

HubError                     everything below; ``str()`` is one sentence with the reason
├── MissingCredentials       neither a token nor a username and password were given
├── InvalidCommand           a command that is not one the hub takes (a misspelt name ...)
├── HubUnreachable           no answer at all: refused, unresolvable, timed out
├── ApiError                 the hub answered with an error (``status``, ``reason``)
│   ├── Unauthorized         401  no, wrong, expired or revoked credentials
│   ├── Forbidden            403  the role or token lacks the permission
│   ├── NotFound             404  no such vehicle, flight, token ...
│   ├── Conflict             409  vehicle offline, the flight controller kept its value ...
│   ├── PayloadTooLarge      413
│   ├── Unprocessable        422  ``problems`` names each field; ``violations`` each safety rule
│   ├── RateLimited          429  ``retry_after`` seconds
│   ├── Unavailable          503  the hub's database is down; ``retry_after`` seconds
│   └── GatewayTimeout       504  the agent or the flight controller did not answer in time
├── CommandRefused           the command reached the flight controller, which refused it
│                            (or did not answer); ``outcome`` is the hub's CommandOutcome
├── FeedClosed               the live feed was closed for good (``code``, ``reason``)
└── WaitTimedOut             ``FleetWatch.wait_until`` gave up: what it waited for never held

The hub's error bodies are ``{"detail": "<sentence>"}``, or for a 422 ``{"detail": [{"loc",
"msg", "type"}, ...]}`` (plus ``violations`` for a safety refusal); ``reason`` is that
sentence, or the problems joined as ``field: rule; ...``.
"""

from __future__ import annotations

from typing import Any

import httpx

from gcs_client.models import CommandOutcome, ValidationProblem


class HubError(Exception):
    """Anything that kept the client from getting what it asked for."""

    def __init__(self, reason: str) -> None:
        super().__init__(reason)
        self.reason = reason


class MissingCredentials(HubError):
    pass


class HubUnreachable(HubError):
    pass


class InvalidCommand(HubError):
    pass


class ApiError(HubError):
    """The hub answered ``status``; ``reason`` is what it said, ``body`` the whole answer."""

    status = 0

    def __init__(self, method: str, path: str, status: int, reason: str, body: Any) -> None:
        super().__init__(reason)
        self.method = method
        self.path = path
        self.status = status
        self.body = body

    def __str__(self) -> str:
        return f"{self.method} {self.path} answered {self.status}: {self.reason}"


class Unauthorized(ApiError):
    pass


class Forbidden(ApiError):
    pass


class NotFound(ApiError):
    pass


class Conflict(ApiError):
    pass


class PayloadTooLarge(ApiError):
    pass


class Unprocessable(ApiError):
    @property
    def problems(self) -> list[ValidationProblem]:
        """Each field the hub refused and the rule it broke (empty for a safety refusal)."""
        detail = self.body.get("detail") if isinstance(self.body, dict) else None
        if not isinstance(detail, list):
            return []
        return [ValidationProblem.model_validate(item) for item in detail]

    @property
    def violations(self) -> list[dict[str, Any]]:
        """The safety rules a command or mission broke, each with its name and limit."""
        found = self.body.get("violations") if isinstance(self.body, dict) else None
        return list(found or [])


class RateLimited(ApiError):
    retry_after: float | None = None


class Unavailable(ApiError):
    retry_after: float | None = None


class GatewayTimeout(ApiError):
    pass


class CommandRefused(HubError):
    """The flight controller's verdict was not 'accepted' (refused, timeout, failed)."""

    def __init__(self, vehicle_id: str, command: str, outcome: CommandOutcome) -> None:
        super().__init__(f"{command} on {vehicle_id}: {outcome.status}: {outcome.message}")
        self.vehicle_id = vehicle_id
        self.command = command
        self.outcome = outcome


class FeedClosed(HubError):
    """The hub closed the live feed and reconnecting cannot help (see docs/websockets.md
    for the codes: 4401 credentials, 4403 not allowed, ...)."""

    def __init__(self, code: int, reason: str) -> None:
        super().__init__(f"the hub closed the live feed: {code} {reason}".rstrip())
        self.code = code


BY_STATUS: dict[int, type[ApiError]] = {
    401: Unauthorized,
    403: Forbidden,
    404: NotFound,
    409: Conflict,
    413: PayloadTooLarge,
    422: Unprocessable,
    429: RateLimited,
    503: Unavailable,
    504: GatewayTimeout,
}


def api_error(response: httpx.Response) -> ApiError:
    """The exception for an error answer, carrying the hub's reason."""
    try:
        body: Any = response.json()
    except ValueError:
        body = {"detail": response.text or response.reason_phrase}
    detail = body.get("detail") if isinstance(body, dict) else body
    if isinstance(detail, list):  # a 422: one entry per bad field or broken rule
        reason = "; ".join(_problem(item) for item in detail)
    else:
        reason = str(detail)
    kind = BY_STATUS.get(response.status_code, ApiError)
    error = kind(
        response.request.method, response.request.url.path, response.status_code, reason, body
    )
    if isinstance(error, RateLimited | Unavailable):
        retry_after = response.headers.get("Retry-After")
        error.retry_after = float(retry_after) if retry_after else None
    return error


def _problem(item: Any) -> str:
    if isinstance(item, dict) and "msg" in item:
        where = ".".join(str(part) for part in item.get("loc", []))
        return f"{where}: {item['msg']}"
    return str(item)


class WaitTimedOut(HubError):
    pass
