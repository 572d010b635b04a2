"""The one authorization policy. Every REST route and WebSocket message is checked here.

A later rule (a vehicle's manual-control lease, say) joins ``authorize`` and so
applies to every caller at once.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from enum import StrEnum
from typing import Literal

from backend.errors import Forbidden


class Role(StrEnum):
    VIEWER = "viewer"  # sees everything, commands nothing
    OPERATOR = "operator"  # commands and plans
    ADMIN = "admin"  # users, vehicles, settings


class Permission(StrEnum):
    READ = "read"  # fleet state, telemetry, configuration, one's own tokens
    COMMAND = "command"  # vehicle commands, mission checks
    AUDIT = "audit"  # the audit log
    ADMIN = "admin"  # users, enrolment, safety rails, overrides
    AGENT = "agent"  # speaking for one vehicle (agent tokens only)


# What each scope of a user's token allows: the OAuth2 scopes of the OpenAPI document.
USER_SCOPES: dict[Permission, str] = {
    Permission.READ: "Fleet state, telemetry, flights, configuration, one's own tokens",
    Permission.COMMAND: "Vehicle commands, parameters, missions, mission checks",
    Permission.AUDIT: "The audit log",
    Permission.ADMIN: "Users, vehicle enrolment, safety rails, safety overrides",
}


# The scopes a user's token may be given, as the API takes them (`agent` is for agent
# tokens only, which enrolment issues: a scope error must not offer it).
UserScope = Literal["read", "command", "audit", "admin"]


def scope_list(scopes: frozenset[Permission] | set[Permission]) -> str:
    """Scopes as a reader writes them: ``'admin', 'audit'`` (sorted, no enum reprs)."""
    return ", ".join(f"'{scope.value}'" for scope in sorted(scopes)) or "none"


# Routes anyone may call (logging in, the health probe).
PUBLIC = "public"

ROLE_PERMISSIONS: dict[Role, frozenset[Permission]] = {
    Role.VIEWER: frozenset({Permission.READ}),
    Role.OPERATOR: frozenset({Permission.READ, Permission.COMMAND, Permission.AUDIT}),
    Role.ADMIN: frozenset(
        {Permission.READ, Permission.COMMAND, Permission.AUDIT, Permission.ADMIN}
    ),
}
USER_PERMISSIONS = ROLE_PERMISSIONS[Role.ADMIN]


@dataclass(frozen=True)
class Principal:
    """An authenticated caller: a user (through a session, access or API token) or an agent."""

    name: str
    role: str  # a Role, or "agent"
    permissions: frozenset[Permission]
    vehicle_id: str | None = None  # agents speak for exactly this vehicle
    token_id: int | None = None
    # A user's token: its kind (session, access or api), its name (api tokens) and the
    # scopes it was narrowed to (None: the role's permissions, unnarrowed).
    token_kind: str = ""
    token_name: str = ""
    scopes: frozenset[Permission] | None = None
    # When the token stops being valid (Unix seconds; None: until revoked), so that a
    # cached principal and a live socket end with it.
    expires_at: float | None = None
    extra: dict[str, str] = field(default_factory=dict, compare=False)

    @property
    def is_agent(self) -> bool:
        return self.vehicle_id is not None


def user_principal(
    name: str,
    role: Role,
    scopes: frozenset[Permission] | None,
    token_id: int,
    expires_at: float | None = None,
    token_kind: str = "",
    token_name: str = "",
) -> Principal:
    """A user's principal: the role's permissions, narrowed by the token's scopes."""
    allowed = ROLE_PERMISSIONS[role]
    return Principal(
        name=name,
        role=role.value,
        permissions=allowed if scopes is None else allowed & scopes,
        token_id=token_id,
        token_kind=token_kind,
        token_name=token_name,
        scopes=scopes,
        expires_at=expires_at,
    )


def agent_principal(vehicle_id: str, token_id: int) -> Principal:
    return Principal(
        name=f"agent:{vehicle_id}",
        role="agent",
        permissions=frozenset({Permission.AGENT}),
        vehicle_id=vehicle_id,
        token_id=token_id,
        token_kind="agent",
    )


def authorize(principal: Principal, needed: Permission, vehicle_id: str | None = None) -> None:
    """Raise Forbidden unless ``principal`` may do what ``needed`` covers (on ``vehicle_id``)."""
    if needed not in principal.permissions:
        raise Forbidden(_lacking(principal, needed))
    if principal.is_agent and vehicle_id is not None and vehicle_id != principal.vehicle_id:
        raise Forbidden(f"this agent token belongs to {principal.vehicle_id!r}, not {vehicle_id!r}")


def _lacking(principal: Principal, needed: Permission) -> str:
    """Blame what is short: the token's scopes when the role has the permission, else the
    role (an admin's read-only token lacks 'command' because of its scopes)."""
    if principal.scopes is not None and needed not in principal.scopes:
        role_permissions = next(
            (granted for role, granted in ROLE_PERMISSIONS.items() if role == principal.role),
            frozenset(),
        )
        if needed in role_permissions:
            token = f"token {principal.token_name!r}" if principal.token_name else "token"
            return (
                f"this {token} lacks the '{needed}' permission: its scopes are "
                f"{scope_list(principal.scopes)} (the {principal.role} role has it)"
            )
    return f"{principal.name} ({principal.role} role) lacks the '{needed}' permission"


# What each WebSocket message type needs, by the ``type`` field. A message type missing
# here is refused, and the test suite checks every type in protocol.messages is listed.
CLIENT_MESSAGE_PERMISSIONS: dict[str, Permission] = {
    "ping": Permission.READ,
    "control": Permission.COMMAND,
    "manual": Permission.COMMAND,
    "subscribe_scans": Permission.READ,
    "unsubscribe_scans": Permission.READ,
    "subscribe_map": Permission.READ,
    "unsubscribe_map": Permission.READ,
}
AGENT_MESSAGE_PERMISSIONS: dict[str, Permission] = {
    "hello": Permission.AGENT,
    "telemetry": Permission.AGENT,
    "live_state": Permission.AGENT,
    "event": Permission.AGENT,
    "command_result": Permission.AGENT,
    "unavailable": Permission.AGENT,
    "pong": Permission.AGENT,
    "manual_applied": Permission.AGENT,
    "scan_source_stats": Permission.AGENT,
    "modes": Permission.AGENT,
}


def authorize_message(
    principal: Principal,
    message_type: str,
    table: dict[str, Permission],
    vehicle_id: str | None = None,
) -> None:
    needed = table.get(message_type)
    if needed is None:
        raise Forbidden(f"message type {message_type!r} has no policy")
    authorize(principal, needed, vehicle_id)
