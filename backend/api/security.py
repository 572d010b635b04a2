"""Authentication at the API edge, and the router that makes every route name its permission.

``SecuredRouter`` refuses to register a route that does not declare a permission (through
``requires(...)``), and puts the check in front of it. So the policy has one choke point,
and a new route without a policy fails at import time, not in production.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Annotated, Any

from fastapi import APIRouter, Depends, Request
from fastapi.params import Depends as DependsParam
from fastapi.security import OAuth2PasswordBearer
from starlette.requests import HTTPConnection

from backend.api.deps import get_accounts, get_denials
from backend.api.finite_json import FiniteJsonRoute
from backend.audit import AuditAction, AuditEntry, principal_audit_entry
from backend.auth.credentials import presented_principal, presented_token
from backend.auth.policy import PUBLIC, USER_SCOPES, Permission, Principal, authorize
from backend.errors import Forbidden, Unauthenticated

PERMISSION_KEY = "x-required-permission"

# Declares the bearer scheme in the OpenAPI document (the docs' "Authorize" button).
# Its scopes are the permissions a user's token may be narrowed to.
bearer_scheme = OAuth2PasswordBearer(
    tokenUrl="/api/v1/auth/token",
    scopes={scope.value: text for scope, text in USER_SCOPES.items()},
    auto_error=False,
)


def requires(permission: Permission | str) -> dict[str, Any]:
    """The ``openapi_extra`` that declares a route's permission (or ``PUBLIC``)."""
    return {PERMISSION_KEY: str(permission)}


def client_address(connection: HTTPConnection) -> str:
    return connection.client.host if connection.client else "unknown"


async def principal_of(connection: HTTPConnection) -> Principal | None:
    return await presented_principal(connection, get_accounts(connection))


async def get_principal(
    request: Request, _bearer: Annotated[str | None, Depends(bearer_scheme)]
) -> Principal:
    principal = await principal_of(request)
    if principal is None:
        if presented_token(request) is None:
            raise Unauthenticated("not authenticated: log in or send a bearer token")
        raise Unauthenticated("the token is invalid, expired or revoked")
    request.state.principal = principal
    return principal


CurrentPrincipal = Annotated[Principal, Depends(get_principal)]


def _authorizer(permission: Permission) -> Callable[..., Any]:
    async def check(request: Request, principal: CurrentPrincipal) -> None:
        try:
            authorize(principal, permission, request.path_params.get("vehicle_id"))
        except Forbidden as refusal:
            if permission != Permission.READ:
                # A refused attempt to act is itself worth a line in the audit log.
                action = f"{request.method} {request.url.path}"
                entry = audit_entry(
                    request, principal, AuditAction.DENIED, action, "denied", reason=str(refusal)
                )
                # Grouped by the route's template, so a loop over vehicle ids or paths
                # is one principal's one refusal, not a row per request.
                route = getattr(request.scope.get("route"), "path", request.url.path)
                key = f"{request.method} {route}"
                await get_denials(request).record_denial(entry, key, str(refusal))
            raise refusal

    return check


class SecuredRouter(APIRouter):
    """An APIRouter whose every route must declare ``openapi_extra=requires(...)``."""

    def __init__(self, **kwargs: Any) -> None:
        kwargs.setdefault("route_class", FiniteJsonRoute)  # NaN and Infinity are refused
        super().__init__(**kwargs)

    def add_api_route(self, path: str, endpoint: Callable[..., Any], **kwargs: Any) -> None:
        extra = kwargs.get("openapi_extra") or {}
        declared = extra.get(PERMISSION_KEY)
        if declared is None:
            raise RuntimeError(f"route {path} declares no permission: add requires(...)")
        if declared != PUBLIC:
            dependencies: list[DependsParam] = list(kwargs.get("dependencies") or [])
            dependencies.insert(0, Depends(_authorizer(Permission(declared))))
            kwargs["dependencies"] = dependencies
            responses = dict(kwargs.get("responses") or {})
            responses.setdefault(401, {"description": "Not authenticated"})
            responses.setdefault(403, {"description": f"Needs the '{declared}' permission"})
            kwargs["responses"] = responses
        super().add_api_route(path, endpoint, **kwargs)


def audit_entry(
    request: HTTPConnection,
    principal: Principal | None,
    action: AuditAction,
    target: str,
    outcome: str,
    **detail: Any,
) -> AuditEntry:
    if principal is None:
        return AuditEntry(
            actor="anonymous",
            role="",
            source=client_address(request),
            action=action,
            target=target,
            outcome=outcome,
            detail=detail,
        )
    return principal_audit_entry(
        principal, client_address(request), action, target, outcome, detail
    )
