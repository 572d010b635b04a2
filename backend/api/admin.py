"""Administration: users, vehicle enrolment (agent tokens) and the audit log."""

from __future__ import annotations

import asyncio
import json
from typing import Annotated, Any, Literal

from fastapi import Depends, Path, Query, Request, Response, status
from pydantic import BaseModel, Field, ValidationInfo, field_validator
from pydantic_core import PydanticCustomError

from backend.api.deps import AccountsDep, AuditDep, AuditLogDep, PasswordsDep, SessionsDep
from backend.api.security import CurrentPrincipal, SecuredRouter, audit_entry, requires
from backend.audit import AuditAction, AuditQuery
from backend.auth.password_policy import MIN_LENGTH, password_problem
from backend.auth.policy import Permission, Role
from backend.errors import InvalidRequest
from backend.storage.models import UserRow
from protocol.messages import Boolean, VehicleId

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
    disabled: Boolean | None = None
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
    actor: str = Field(description="The user (or agent:<vehicle>, provisioning, anonymous)")
    role: str
    source: str = Field(description="The client's address")
    action: AuditAction
    target: str
    outcome: str = Field(description="ok, refused, failed or denied")
    detail: dict[str, Any]
    token_kind: Literal["session", "access", "api", "agent"] | None = Field(
        default=None,
        description="The credential the actor used: a dashboard session, an access token "
        "(/auth/token), an API token or an agent token; null for anonymous attempts, the "
        "hub itself, and entries from before it was recorded",
    )
    token_id: int | None = Field(
        default=None,
        description="That token's id (an API token's as in /auth/api-tokens, an agent "
        "token's as in /agent-tokens)",
    )
    token: str | None = Field(
        default=None,
        description="An API token's name, so an integration's acts are told from its user's",
    )


class AuditPage(BaseModel):
    entries: list[AuditRecord]
    next_before_id: int | None = Field(
        description="Pass as before_id for the next (older) page; null on the last page"
    )


# The audit log's query parameters: any other is refused (422), so a misspelt filter
# does not silently answer with the whole log.
AUDIT_FILTERS = ("actor", "action", "target", "since", "until", "before_id", "limit")


def _known_filters_only(request: Request) -> None:
    unknown = sorted(set(request.query_params) - set(AUDIT_FILTERS))
    if unknown:
        valid = ", ".join(AUDIT_FILTERS)
        raise InvalidRequest(
            unknown[0], f"unknown filter {unknown[0]!r}; valid filters: {valid}", "query"
        )


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
async def list_users(accounts: AccountsDep) -> list[User]:
    return [_user(row) for row in await asyncio.to_thread(accounts.users)]


@router.post(
    "/users",
    response_model=User,
    status_code=status.HTTP_201_CREATED,
    openapi_extra=requires(Permission.ADMIN),
)
async def create_user(
    body: UserCreate,
    request: Request,
    principal: CurrentPrincipal,
    passwords: PasswordsDep,
    accounts: AccountsDep,
    audit: AuditDep,
) -> User:
    # Hashing runs on the password threads, bounded like a login.
    row = await passwords.run(accounts.create_user, body.username, body.password, body.role)
    await audit.record(
        audit_entry(
            request, principal, AuditAction.USER_CREATE, body.username, "ok", role=body.role
        )
    )
    return _user(row)


@router.patch("/users/{username}", response_model=User, openapi_extra=requires(Permission.ADMIN))
async def update_user(
    username: Annotated[str, Path(max_length=64)],
    body: UserUpdate,
    request: Request,
    principal: CurrentPrincipal,
    passwords: PasswordsDep,
    accounts: AccountsDep,
    sessions: SessionsDep,
    audit: AuditDep,
) -> User:
    """Change a role, disable an account (ends its sessions) or reset a password."""
    run = asyncio.to_thread if body.password is None else passwords.run
    row = await run(accounts.update_user, username, body.role, body.disabled, body.password)
    if body.disabled or body.password is not None:
        await sessions.drop_user_feeds(user=username)  # their sessions were just revoked
    changes = body.model_dump(exclude_none=True, exclude={"password"})
    if body.password is not None:
        changes["password"] = "changed"
    await audit.record(
        audit_entry(request, principal, AuditAction.USER_UPDATE, username, "ok", **changes)
    )
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
    accounts: AccountsDep,
    audit: AuditDep,
) -> IssuedAgentToken:
    """Enrol a vehicle (new or known): a token its agent presents. Stored only as a hash."""
    issued = await asyncio.to_thread(accounts.enrol_vehicle, vehicle_id, principal.name)
    await audit.record(
        audit_entry(
            request, principal, AuditAction.AGENT_TOKEN_CREATE, vehicle_id, "ok", id=issued.id
        )
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
    accounts: AccountsDep, vehicle_id: Annotated[str | None, Query(max_length=64)] = None
) -> list[AgentToken]:
    rows = await asyncio.to_thread(accounts.agent_tokens, vehicle_id)
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
    accounts: AccountsDep,
    sessions: SessionsDep,
    audit: AuditDep,
) -> Response:
    """Revoke an agent token; a live connection using it is closed at once."""
    row = await asyncio.to_thread(accounts.revoke_agent_token, token_id)
    await sessions.drop_agent_token(row.id, row.vehicle_id)
    await audit.record(
        audit_entry(
            request, principal, AuditAction.AGENT_TOKEN_REVOKE, row.vehicle_id, "ok", id=row.id
        )
    )
    return Response(status_code=status.HTTP_204_NO_CONTENT)


@router.get(
    "/audit",
    response_model=AuditPage,
    openapi_extra=requires(Permission.AUDIT),
    dependencies=[Depends(_known_filters_only)],
)
async def audit_log(
    trail: AuditLogDep,
    actor: Annotated[str | None, Query(max_length=80)] = None,
    action: Annotated[AuditAction | None, Query(description="One of the actions listed")] = None,
    target: Annotated[str | None, Query(max_length=128)] = None,
    since: Annotated[float | None, Query(description="Unix seconds")] = None,
    until: Annotated[float | None, Query(description="Unix seconds")] = None,
    before_id: Annotated[
        int | None, Query(ge=1, le=2**62, description="page: entries older than")
    ] = None,
    limit: Annotated[int, Query(ge=1, le=1000)] = 100,
) -> AuditPage:
    """Audit entries, newest first, a page at a time (``next_before_id``). An unknown
    filter or action is refused (422, naming the valid ones)."""
    query = AuditQuery(actor, action, target, since, until, before_id, limit)
    rows = await asyncio.to_thread(trail.query, query)
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
                token_kind=row.token_kind,
                token_id=row.token_id,
                token=row.token_name,
            )
            for row in rows
        ],
        next_before_id=rows[-1].id if len(rows) == limit else None,
    )
