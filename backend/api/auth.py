"""Logging in (dashboard sessions, the OAuth2 password flow) and one's own API tokens."""

from __future__ import annotations

import asyncio
from dataclasses import dataclass
from typing import Annotated

from fastapi import Depends, Path, Request, Response, status
from fastapi.security import OAuth2PasswordRequestForm
from pydantic import BaseModel, BeforeValidator, Field, Strict

from backend.api.deps import (
    AccountsDep,
    AuditDep,
    AuditRecorder,
    LoginAddressLimiterDep,
    LoginLimiterDep,
    PasswordsDep,
    SessionsDep,
    SettingsDep,
)
from backend.api.security import (
    CurrentPrincipal,
    SecuredRouter,
    audit_entry,
    client_address,
    requires,
)
from backend.audit import AuditAction
from backend.auth.accounts import Accounts
from backend.auth.credentials import SESSION_COOKIE
from backend.auth.password_work import PasswordWork
from backend.auth.policy import (
    PUBLIC,
    ROLE_PERMISSIONS,
    USER_SCOPES,
    Permission,
    Role,
    UserScope,
    scope_list,
    user_principal,
)
from backend.auth.rate_limit import RateLimiter
from backend.errors import Forbidden, InvalidRequest, RateLimited, Unauthenticated
from backend.storage.models import UserRow
from protocol.messages import whole_number

router = SecuredRouter(prefix="/auth", tags=["auth"])

WRONG_CREDENTIALS = "wrong username or password"
MAX_USERNAME = 64
MAX_PASSWORD = 1024


class LoginRequest(BaseModel):
    username: str = Field(min_length=1, max_length=64)
    password: str = Field(min_length=1, max_length=1024)


class Identity(BaseModel):
    username: str
    role: str
    permissions: list[str]
    expires_at: float | None = Field(
        default=None, description="When the token (or session) used ends; null: never"
    )


class AccessToken(BaseModel):
    access_token: str
    token_type: str = "bearer"
    expires_in: int


API_TOKEN_DAYS = 90  # an API token's lifetime unless its creator asks for another
# An Integer whose bounds the schema states (see protocol.messages.Integer).
ExpiryDays = Annotated[int, Strict(), Field(ge=1, le=3650), BeforeValidator(whole_number)]


class ApiTokenRequest(BaseModel):
    name: str = Field(min_length=1, max_length=128)
    scopes: list[UserScope] | None = Field(
        default=None, description="Permissions to keep (a subset of the role's); all if unset"
    )
    expires_in_days: ExpiryDays | None = Field(
        default=API_TOKEN_DAYS,
        description=f"Days until the token expires, 1 to 3,650 ({API_TOKEN_DAYS} if not "
        "given); null: it never expires (revoke it when it is no longer needed)",
    )


class ApiToken(BaseModel):
    id: int
    name: str
    scopes: list[str]
    created_at: float
    expires_at: float | None
    revoked: bool


class IssuedApiToken(ApiToken):
    token: str = Field(description="Shown once; store it now")


@dataclass(frozen=True)
class PasswordCheck:
    """What checking a login's password uses: its rate limits, the hashing capacity,
    the accounts, and the audit log that records a refusal."""

    login_limiter: RateLimiter
    login_address_limiter: RateLimiter
    passwords: PasswordWork
    accounts: Accounts
    audit: AuditRecorder


def _password_check(
    login_limiter: LoginLimiterDep,
    login_address_limiter: LoginAddressLimiterDep,
    passwords: PasswordsDep,
    accounts: AccountsDep,
    audit: AuditDep,
) -> PasswordCheck:
    return PasswordCheck(login_limiter, login_address_limiter, passwords, accounts, audit)


PasswordCheckDep = Annotated[PasswordCheck, Depends(_password_check)]


async def _login(check: PasswordCheck, request: Request, username: str, password: str) -> UserRow:
    """Check a password under the login rate limits, auditing the attempt.

    Failures count per (address, user name) and per address. Not per user name alone:
    then anyone could lock a user out with a few wrong passwords from anywhere, and the
    user's right password from a fresh address would be refused too. Guessing one name
    from many addresses is bounded by the password-hashing capacity instead.
    """
    address = client_address(request)
    pair = f"{address}|{username[:MAX_USERNAME]}"
    check.login_limiter.check(pair, "login attempts")
    check.login_address_limiter.check(address, "login attempts")
    # Counted before the (slow) password check, so concurrent guesses cannot all slip
    # in under the limit; a success, or a check that never ran, takes its attempt back.
    check.login_limiter.hit(pair)
    check.login_address_limiter.hit(address)
    user = None
    if len(username) <= MAX_USERNAME and len(password) <= MAX_PASSWORD:
        try:
            user = await check.passwords.run(check.accounts.authenticate, username, password)
        except RateLimited:
            check.login_limiter.forget_one(pair)
            check.login_address_limiter.forget_one(address)
            raise
    if user is None:
        await check.audit.record(
            audit_entry(request, None, AuditAction.LOGIN, username[:MAX_USERNAME], "denied")
        )
        raise Unauthenticated(WRONG_CREDENTIALS)
    check.login_limiter.reset(pair)
    check.login_address_limiter.forget_one(address)
    return user


def _identity(user: UserRow, expires_at: float | None) -> Identity:
    permissions = sorted(ROLE_PERMISSIONS[Role(user.role)])
    return Identity(
        username=user.username, role=user.role, permissions=permissions, expires_at=expires_at
    )


@router.post("/login", response_model=Identity, openapi_extra=requires(PUBLIC))
async def login(
    body: LoginRequest,
    request: Request,
    response: Response,
    check: PasswordCheckDep,
    settings: SettingsDep,
    accounts: AccountsDep,
    audit: AuditDep,
) -> Identity:
    """Dashboard login: sets an HTTP-only session cookie."""
    user = await _login(check, request, body.username, body.password)
    issued = await asyncio.to_thread(
        accounts.issue_user_token, user, "session", settings.session_ttl_s
    )
    response.set_cookie(
        SESSION_COOKIE,
        issued.token,
        max_age=int(settings.session_ttl_s),
        httponly=True,
        secure=settings.cookie_secure,
        samesite="strict",
        path="/",
    )
    who = user_principal(user.username, Role(user.role), None, issued.id, token_kind="session")
    await audit.record(
        audit_entry(request, who, AuditAction.LOGIN, user.username, "ok", kind="session")
    )
    return _identity(user, issued.expires_at)


FORM_TYPES = ("application/x-www-form-urlencoded", "multipart/form-data")


def _form_only(request: Request) -> None:
    """The password flow takes a form (RFC 6749 4.3.2): a JSON body would otherwise be
    answered "username: Field required", which sends a client looking in the wrong place."""
    media_type = request.headers.get("content-type", "").split(";")[0].strip().lower()
    if media_type not in FORM_TYPES:
        raise InvalidRequest(
            "content-type",
            "this route takes a form (application/x-www-form-urlencoded) with username, "
            f"password and optionally scope, as OAuth2's password flow; got {media_type or 'none'}"
            " (for a JSON login use POST /api/v1/auth/login)",
            "header",
        )


@router.post(
    "/token",
    response_model=AccessToken,
    openapi_extra=requires(PUBLIC),
    dependencies=[Depends(_form_only)],
)
async def token(
    form: Annotated[OAuth2PasswordRequestForm, Depends()],
    request: Request,
    check: PasswordCheckDep,
    settings: SettingsDep,
    accounts: AccountsDep,
    audit: AuditDep,
) -> AccessToken:
    """OAuth2 password flow for integrations: returns a bearer access token.

    ``scope`` may narrow the token to some of the role's permissions (space-separated).
    """
    user = await _login(check, request, form.username, form.password)
    scopes = _requested_scopes(form.scopes, Role(user.role))
    ttl = settings.access_token_ttl_s
    issued = await asyncio.to_thread(accounts.issue_user_token, user, "access", ttl, scopes)
    who = user_principal(user.username, Role(user.role), scopes, issued.id, token_kind="access")
    await audit.record(
        audit_entry(request, who, AuditAction.LOGIN, user.username, "ok", kind="access")
    )
    return AccessToken(access_token=issued.token, expires_in=int(ttl))


def _requested_scopes(requested: list[str], role: Role) -> frozenset[Permission] | None:
    if not requested:
        return None
    valid = {scope.value for scope in USER_SCOPES}
    unknown = [scope for scope in dict.fromkeys(requested) if scope not in valid]
    if unknown:
        named = ", ".join(repr(scope) for scope in unknown)
        raise InvalidRequest(
            "scope",
            f"unknown scope {named}; valid scopes: {scope_list(frozenset(USER_SCOPES))}",
        )
    scopes = frozenset(Permission(scope) for scope in requested)
    beyond = scopes - ROLE_PERMISSIONS[role]
    if beyond:
        raise Forbidden(
            f"the {role.value} role cannot have the scopes {scope_list(beyond)}; "
            f"it may have {scope_list(ROLE_PERMISSIONS[role])}"
        )
    return scopes


@router.post(
    "/logout", status_code=status.HTTP_204_NO_CONTENT, openapi_extra=requires(Permission.READ)
)
async def logout(
    request: Request,
    principal: CurrentPrincipal,
    accounts: AccountsDep,
    sessions: SessionsDep,
    audit: AuditDep,
) -> Response:
    """Ends the session (or revokes the bearer token used)."""
    if principal.token_id is not None:
        await asyncio.to_thread(accounts.revoke_user_token, principal.token_id, None)
        await sessions.drop_user_feeds(token_id=principal.token_id)
    await audit.record(audit_entry(request, principal, AuditAction.LOGOUT, principal.name, "ok"))
    response = Response(status_code=status.HTTP_204_NO_CONTENT)
    response.delete_cookie(SESSION_COOKIE, path="/")
    return response


@router.get("/me", response_model=Identity, openapi_extra=requires(Permission.READ))
async def me(principal: CurrentPrincipal) -> Identity:
    return Identity(
        username=principal.name,
        role=principal.role,
        permissions=sorted(principal.permissions),
        expires_at=principal.expires_at,
    )


@router.get("/api-tokens", response_model=list[ApiToken], openapi_extra=requires(Permission.READ))
async def list_api_tokens(principal: CurrentPrincipal, accounts: AccountsDep) -> list[ApiToken]:
    """The caller's own API tokens (never their values)."""
    rows = await asyncio.to_thread(accounts.api_tokens, principal.name)
    return [
        ApiToken(
            id=row.id,
            name=row.name,
            scopes=row.scopes.split(","),
            created_at=row.created_at,
            expires_at=row.expires_at,
            revoked=row.revoked_at is not None,
        )
        for row in rows
    ]


@router.post(
    "/api-tokens",
    response_model=IssuedApiToken,
    status_code=status.HTTP_201_CREATED,
    openapi_extra=requires(Permission.READ),
)
async def create_api_token(
    body: ApiTokenRequest,
    request: Request,
    principal: CurrentPrincipal,
    accounts: AccountsDep,
    audit: AuditDep,
) -> IssuedApiToken:
    """A bearer token for an integration, scoped to some of the caller's rights. It expires
    after ``expires_in_days`` (90 by default; 1 to 3,650), or never when that is null."""
    user = await asyncio.to_thread(accounts.user, principal.name)
    role_scopes = ROLE_PERMISSIONS[Role(user.role)]
    scopes = (
        frozenset(Permission(scope) for scope in body.scopes)
        if body.scopes is not None
        else role_scopes
    )
    # A token never carries more than the session that created it.
    if not scopes <= principal.permissions:
        raise Forbidden(
            f"cannot grant the scopes {scope_list(scopes - principal.permissions)}: a new token "
            f"carries at most the permissions of the one that creates it "
            f"({scope_list(principal.permissions)})"
        )
    ttl = body.expires_in_days * 86400 if body.expires_in_days else None
    issued = await asyncio.to_thread(accounts.issue_user_token, user, "api", ttl, scopes, body.name)
    await audit.record(
        audit_entry(
            request, principal, AuditAction.TOKEN_CREATE, body.name, "ok", scopes=sorted(scopes)
        )
    )
    return IssuedApiToken(
        id=issued.id,
        name=body.name,
        scopes=sorted(scopes),
        created_at=issued.created_at,
        expires_at=issued.expires_at,
        revoked=False,
        token=issued.token,
    )


@router.delete(
    "/api-tokens/{token_id}",
    status_code=status.HTTP_204_NO_CONTENT,
    openapi_extra=requires(Permission.READ),
)
async def revoke_api_token(
    token_id: Annotated[int, Path(ge=1, le=2**62)],
    request: Request,
    principal: CurrentPrincipal,
    accounts: AccountsDep,
    sessions: SessionsDep,
    audit: AuditDep,
) -> Response:
    await asyncio.to_thread(accounts.revoke_user_token, token_id, principal.name)
    await sessions.drop_user_feeds(token_id=token_id)
    await audit.record(
        audit_entry(request, principal, AuditAction.TOKEN_REVOKE, str(token_id), "ok")
    )
    return Response(status_code=status.HTTP_204_NO_CONTENT)
