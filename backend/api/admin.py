"""Administration: users, vehicle enrolment (agent tokens) and the audit log."""

from __future__ import annotations

import asyncio
import json
from typing import Annotated, Any

from fastapi import Path, Query, Request, Response, status
from pydantic import BaseModel, Field, ValidationInfo, field_validator
from pydantic_core import PydanticCustomError

from backend.api.deps import HubDep
from backend.api.security import CurrentPrincipal, SecuredRouter, audit_entry, requires
from backend.audit import AuditQuery
from backend.auth.password_policy import MIN_LENGTH, password_problem
from backend.auth.policy import Permission, Role
from backend.storage.models import UserRow
from protocol.messages import VehicleId

router = SecuredRouter(tags=["admin"])

Username = Annotated[str, Field(pattern=r"^[A-Za-z0-9_.@-]{1,64}$")]


Password = Annotated[
    str,
    Field(
        min_length=MIN_LENGTH,
        max_length=1024,
        description=f"at least {MIN_LENGTH} characters, and not a common or guessable one",
    ),
]


class UserCreate(BaseModel):
    username: Username
    password: Password
    role: Role

    @field_validator("password")
    @classmethod
    def _strong_password(cls, password: str, info: ValidationInfo) -> str:
        _refuse_weak(password, info.data.get("username"))  # declared before: checked first
        return password


class UserUpdate(BaseModel):
    role: Role | None = None
    disabled: bool | None = None
    password: Password | None = None

    @field_validator("password")
    @classmethod
    def _strong_password(cls, password: str | None) -> str | None:
        if password is not None:
            _refuse_weak(password, None)
        return password


def _refuse_weak(password: str, username: str | None) -> None:
    """The same rule for every role: an operator's account commands vehicles too."""
    problem = password_problem(password, username)
    if problem is not None:
        raise PydanticCustomError("weak_password", "password {problem}", {"problem": problem})


class User(BaseModel):
    username: str
    role: str
    disabled: bool
    created_at: float


class AgentToken(BaseModel):
    id: int
    vehicle_id: str
    created_at: float
    created_by: str
    revoked: bool


class IssuedAgentToken(AgentToken):
    token: str = Field(description="Give it to the vehicle's agent (GCS_AGENT_TOKEN); shown once")


class AuditRecord(BaseModel):
    id: int
    time: float
    actor: str
    role: str
    source: str
    action: str
    target: str
    outcome: str
    detail: dict[str, Any]


class AuditPage(BaseModel):
    entries: list[AuditRecord]


def _detail(stored: str) -> dict[str, Any]:
    try:
        value = json.loads(stored or "{}")
    except json.JSONDecodeError:
        return {"unparsed": stored}
    return value if isinstance(value, dict) else {"value": value}


def _user(row: UserRow) -> User:
    return User(
        username=row.username, role=row.role, disabled=row.disabled, created_at=row.created_at
    )


@router.get("/users", response_model=list[User], openapi_extra=requires(Permission.ADMIN))
async def list_users(hub: HubDep) -> list[User]:
    return [_user(row) for row in await asyncio.to_thread(hub.accounts.users)]


@router.post(
    "/users",
    response_model=User,
    status_code=status.HTTP_201_CREATED,
    openapi_extra=requires(Permission.ADMIN),
)
async def create_user(
    body: UserCreate, request: Request, principal: CurrentPrincipal, hub: HubDep
) -> User:
    # Hashing runs on the password threads, bounded like a login.
    row = await hub.passwords.run(hub.accounts.create_user, body.username, body.password, body.role)
    await hub.record(
        audit_entry(request, principal, "user.create", body.username, "ok", role=body.role)
    )
    return _user(row)


@router.patch("/users/{username}", response_model=User, openapi_extra=requires(Permission.ADMIN))
async def update_user(
    username: Annotated[str, Path(max_length=64)],
    body: UserUpdate,
    request: Request,
    principal: CurrentPrincipal,
    hub: HubDep,
) -> User:
    """Change a role, disable an account (ends its sessions) or reset a password."""
    run = asyncio.to_thread if body.password is None else hub.passwords.run
    row = await run(hub.accounts.update_user, username, body.role, body.disabled, body.password)
    if body.disabled or body.password is not None:
        await hub.drop_user_feeds(user=username)  # their sessions were just revoked
    changes = body.model_dump(exclude_none=True, exclude={"password"})
    if body.password is not None:
        changes["password"] = "changed"
    await hub.record(audit_entry(request, principal, "user.update", username, "ok", **changes))
    return _user(row)


@router.post(
    "/vehicles/{vehicle_id}/agent-tokens",
    response_model=IssuedAgentToken,
    status_code=status.HTTP_201_CREATED,
    openapi_extra=requires(Permission.ADMIN),
)
async def enrol_vehicle(
    vehicle_id: Annotated[VehicleId, Path()],
    request: Request,
    principal: CurrentPrincipal,
    hub: HubDep,
) -> IssuedAgentToken:
    """Enrol a vehicle (new or known): a token its agent presents. Stored only as a hash."""
    issued = await asyncio.to_thread(hub.accounts.enrol_vehicle, vehicle_id, principal.name)
    await hub.record(
        audit_entry(request, principal, "agent_token.create", vehicle_id, "ok", id=issued.id)
    )
    return IssuedAgentToken(
        id=issued.id,
        vehicle_id=vehicle_id,
        created_at=issued.created_at,
        created_by=principal.name,
        revoked=False,
        token=issued.token,
    )


@router.get(
    "/agent-tokens", response_model=list[AgentToken], openapi_extra=requires(Permission.ADMIN)
)
async def list_agent_tokens(
    hub: HubDep, vehicle_id: Annotated[str | None, Query(max_length=64)] = None
) -> list[AgentToken]:
    rows = await asyncio.to_thread(hub.accounts.agent_tokens, vehicle_id)
    return [
        AgentToken(
            id=row.id,
            vehicle_id=row.vehicle_id,
            created_at=row.created_at,
            created_by=row.created_by,
            revoked=row.revoked_at is not None,
        )
        for row in rows
    ]


@router.delete(
    "/agent-tokens/{token_id}",
    status_code=status.HTTP_204_NO_CONTENT,
    openapi_extra=requires(Permission.ADMIN),
)
async def revoke_agent_token(
    token_id: Annotated[int, Path(ge=1, le=2**62)],
    request: Request,
    principal: CurrentPrincipal,
    hub: HubDep,
) -> Response:
    """Revoke an agent token; a live connection using it is closed at once."""
    row = await asyncio.to_thread(hub.accounts.revoke_agent_token, token_id)
    await hub.drop_agent_token(row.id, row.vehicle_id)
    await hub.record(
        audit_entry(request, principal, "agent_token.revoke", row.vehicle_id, "ok", id=row.id)
    )
    return Response(status_code=status.HTTP_204_NO_CONTENT)


@router.get("/audit", response_model=AuditPage, openapi_extra=requires(Permission.AUDIT))
async def audit_log(
    hub: HubDep,
    actor: Annotated[str | None, Query(max_length=80)] = None,
    action: Annotated[str | None, Query(max_length=48)] = None,
    target: Annotated[str | None, Query(max_length=128)] = None,
    since: Annotated[float | None, Query(description="Unix seconds")] = None,
    until: Annotated[float | None, Query(description="Unix seconds")] = None,
    before_id: Annotated[
        int | None, Query(ge=1, le=2**62, description="page: entries older than")
    ] = None,
    limit: Annotated[int, Query(ge=1, le=1000)] = 100,
) -> AuditPage:
    """Audit entries, newest first."""
    query = AuditQuery(actor, action, target, since, until, before_id, limit)
    rows = await asyncio.to_thread(hub.audit.query, query)
    return AuditPage(
        entries=[
            AuditRecord(
                id=row.id,
                time=row.time,
                actor=row.actor,
                role=row.role,
                source=row.source,
                action=row.action,
                target=row.target,
                outcome=row.outcome,
                detail=_detail(row.detail),
            )
            for row in rows
        ]
    )
