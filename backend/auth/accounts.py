"""Users, their tokens, and the vehicles' agent tokens, in the database.

Synchronous, like the other repositories: the API runs these in a worker thread.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Sequence
from dataclasses import dataclass

from sqlalchemy import Engine, func, select, update
from sqlalchemy.exc import IntegrityError, SQLAlchemyError
from sqlalchemy.orm import Session

from backend.auth.policy import (
    Permission,
    Principal,
    Role,
    agent_principal,
    user_principal,
)
from backend.auth.principal_cache import PrincipalCache
from backend.auth.secrets import (
    USER_TOKEN_PREFIXES,
    PasswordCost,
    generate_password,
    hash_password,
    new_token,
    token_digest,
    verify_password,
)
from backend.errors import Conflict, NotFound
from backend.storage.models import AgentTokenRow, UserRow, UserTokenRow

log = logging.getLogger(__name__)

# ``created_by`` of the agent tokens that come from the hub's configuration.
PROVISIONING = "provisioning"


@dataclass(frozen=True)
class IssuedToken:
    """A token as handed out once: the raw value is never stored or shown again."""

    id: int
    token: str
    created_at: float
    expires_at: float | None


def _scopes_text(scopes: frozenset[Permission] | None) -> str:
    return "*" if scopes is None else ",".join(sorted(scopes))


def _parse_scopes(text: str) -> frozenset[Permission] | None:
    return None if text == "*" else frozenset(Permission(s) for s in text.split(",") if s)


class Accounts:
    def __init__(
        self,
        engine: Engine,
        cache: PrincipalCache | None = None,
        password_cost: PasswordCost = "standard",
    ) -> None:
        self.engine = engine
        self.password_cost = password_cost
        # No caching unless asked for (the hub asks): a zero-age cache never answers.
        self.cache = cache or PrincipalCache(fresh_s=0.0, outage_s=0.0)
        self._serving_from_cache = False

    # -- users -------------------------------------------------------------

    def ensure_first_admin(self, username: str, password: str | None) -> str | None:
        """Create the admin ``username`` if there are no users; returns a generated
        password, if any."""
        with Session(self.engine) as session:
            if session.scalar(select(func.count()).select_from(UserRow)):
                return None
        generated = None if password else generate_password()
        self.create_user(username, password or generated or "", Role.ADMIN)
        return generated

    def create_user(self, username: str, password: str, role: Role) -> UserRow:
        row = UserRow(
            username=username,
            password_hash=hash_password(password, self.password_cost),
            role=role.value,
            disabled=False,
            created_at=time.time(),
        )
        try:
            with Session(self.engine, expire_on_commit=False) as session, session.begin():
                session.add(row)
        except IntegrityError:
            raise Conflict(f"user {username!r} already exists") from None
        return row

    def users(self) -> Sequence[UserRow]:
        with Session(self.engine) as session:
            return session.scalars(select(UserRow).order_by(UserRow.username)).all()

    def user(self, username: str) -> UserRow:
        with Session(self.engine) as session:
            row = session.scalar(select(UserRow).where(UserRow.username == username))
        if row is None:
            raise NotFound(f"unknown user {username!r}")
        return row

    def update_user(
        self,
        username: str,
        role: Role | None = None,
        disabled: bool | None = None,
        password: str | None = None,
    ) -> UserRow:
        # A new role, a disabled account or a new password changes what every cached
        # principal of this user may do: forget them all before the write.
        self.cache.revoke(lambda who: not who.is_agent and who.name == username)
        with Session(self.engine, expire_on_commit=False) as session, session.begin():
            row = session.scalar(select(UserRow).where(UserRow.username == username))
            if row is None:
                raise NotFound(f"unknown user {username!r}")
            if role is not None:
                row.role = role.value
            if password is not None:
                row.password_hash = hash_password(password, self.password_cost)
            if disabled is not None:
                row.disabled = disabled
            if disabled or password is not None:
                # A disabled account or a changed password ends every existing session.
                session.execute(
                    update(UserTokenRow)
                    .where(UserTokenRow.user_id == row.id, UserTokenRow.revoked_at.is_(None))
                    .values(revoked_at=time.time())
                )
        return row

    def authenticate(self, username: str, password: str) -> UserRow | None:
        with Session(self.engine) as session:
            row = session.scalar(select(UserRow).where(UserRow.username == username))
        stored_hash = row.password_hash if row is not None else None
        matches = verify_password(stored_hash, password, self.password_cost)
        if not matches or row is None or row.disabled:
            return None
        return row

    # -- user tokens -------------------------------------------------------

    def issue_user_token(
        self,
        user: UserRow,
        kind: str,
        ttl_s: float | None,
        scopes: frozenset[Permission] | None = None,
        name: str = "",
    ) -> IssuedToken:
        token = new_token(kind)
        now = time.time()
        row = UserTokenRow(
            user_id=user.id,
            kind=kind,
            name=name,
            token_hash=token_digest(token),
            scopes=_scopes_text(scopes),
            created_at=now,
            expires_at=now + ttl_s if ttl_s else None,
            revoked_at=None,
        )
        with Session(self.engine, expire_on_commit=False) as session, session.begin():
            session.add(row)
        return IssuedToken(row.id, token, row.created_at, row.expires_at)

    def _user_principal(self, session: Session, digest: str) -> Principal | None:
        query = (
            select(UserTokenRow, UserRow)
            .join(UserRow, UserRow.id == UserTokenRow.user_id)
            .where(UserTokenRow.token_hash == digest)
        )
        found = session.execute(query).first()
        return None if found is None else _live_principal(*found)

    def principal_of_token(
        self, token_id: int, name: str, role: str, kind: str
    ) -> Principal | None:
        """The user behind a user token named by id (a command routed from another hub,
        protocol/routing.py), rebuilt from the database: None unless the token is live,
        its user enabled, and both match the name, role and token kind the message gave."""
        query = (
            select(UserTokenRow, UserRow)
            .join(UserRow, UserRow.id == UserTokenRow.user_id)
            .where(UserTokenRow.id == token_id)
        )
        with Session(self.engine) as session:
            found = session.execute(query).first()
        if found is None:
            return None
        token_row, user = found
        if user.username != name or user.role != role or token_row.kind != kind:
            return None  # a forged or stale identity: the database has the last word
        return _live_principal(token_row, user)

    def revoke_user_token(self, token_id: int, owner: str | None) -> None:
        """Revoke one token; ``owner`` limits it to that user's tokens (None: any, for admins)."""
        self.cache.revoke(lambda who: not who.is_agent and who.token_id == token_id)
        with Session(self.engine) as session, session.begin():
            query = select(UserTokenRow).where(UserTokenRow.id == token_id)
            if owner is not None:
                query = query.join(UserRow, UserRow.id == UserTokenRow.user_id).where(
                    UserRow.username == owner
                )
            row = session.scalar(query)
            if row is None:
                raise NotFound(f"no token {token_id}")
            row.revoked_at = row.revoked_at or time.time()

    def api_tokens(self, username: str) -> Sequence[UserTokenRow]:
        query = (
            select(UserTokenRow)
            .join(UserRow, UserRow.id == UserTokenRow.user_id)
            .where(UserRow.username == username, UserTokenRow.kind == "api")
            .order_by(UserTokenRow.id)
        )
        with Session(self.engine) as session:
            return session.scalars(query).all()

    # -- agent tokens (vehicle enrolment) ----------------------------------

    def enrol_vehicle(self, vehicle_id: str, created_by: str) -> IssuedToken:
        token = new_token("agent")
        row = AgentTokenRow(
            vehicle_id=vehicle_id,
            token_hash=token_digest(token),
            created_at=time.time(),
            created_by=created_by,
            revoked_at=None,
        )
        with Session(self.engine, expire_on_commit=False) as session, session.begin():
            session.add(row)
        return IssuedToken(row.id, token, row.created_at, None)

    def provision_agent_token(self, vehicle_id: str, token: str) -> bool:
        """Enrol a vehicle with a token chosen outside the hub (config management,
        compose files); a no-op if that token is already enrolled."""
        digest = token_digest(token)
        with Session(self.engine) as session, session.begin():
            if session.scalar(select(AgentTokenRow.id).where(AgentTokenRow.token_hash == digest)):
                return False
            session.add(
                AgentTokenRow(
                    vehicle_id=vehicle_id,
                    token_hash=digest,
                    created_at=time.time(),
                    created_by=PROVISIONING,
                    revoked_at=None,
                )
            )
        return True

    def revoke_unprovisioned(self, configured: dict[str, str]) -> list[AgentTokenRow]:
        """Provisioned tokens are exactly the configured ``vehicle: token`` set: revoke each
        live provisioned token that is no longer in it (a rotated or removed one). Tokens
        enrolled through the API are not touched. Returns the rows revoked."""
        kept = {token_digest(token) for token in configured.values()}
        now = time.time()
        with Session(self.engine, expire_on_commit=False) as session, session.begin():
            stale = session.scalars(
                select(AgentTokenRow).where(
                    AgentTokenRow.created_by == PROVISIONING,
                    AgentTokenRow.revoked_at.is_(None),
                )
            ).all()
            revoked = [row for row in stale if row.token_hash not in kept]
            for row in revoked:
                row.revoked_at = now
        ids = {row.id for row in revoked}
        self.cache.revoke(lambda who: who.is_agent and who.token_id in ids)
        return revoked

    def _agent_principal(self, session: Session, digest: str) -> Principal | None:
        row = session.scalar(select(AgentTokenRow).where(AgentTokenRow.token_hash == digest))
        if row is None or row.revoked_at is not None:
            return None
        return agent_principal(row.vehicle_id, row.id)

    # -- the one resolver ----------------------------------------------------

    def resolve_token(self, token: str) -> Principal | None:
        """Whoever ``token`` speaks for: a user (session, access or API token) or a vehicle's
        agent (enrolled here, or provisioned in any form the operator chose); None when it
        is unknown, expired or revoked. Every route and socket resolves tokens here.

        A principal resolved moments ago answers from the cache; while the database is
        unavailable, so does one resolved before the outage (SQLAlchemyError otherwise)."""
        digest = token_digest(token)
        if (cached := self.cache.fresh(digest)) is not None:
            return cached
        generation = self.cache.generation
        try:
            principal = self._look_up(digest, token.startswith(USER_TOKEN_PREFIXES))
        except SQLAlchemyError as error:
            remembered = self.cache.during_outage(digest)
            if remembered is None:
                raise
            if not self._serving_from_cache:  # once per outage, not once per request
                self._serving_from_cache = True
                log.warning("database unavailable (%s): tokens resolve from the cache", error)
            return remembered
        self._serving_from_cache = False
        if principal is None:
            self.cache.forget(digest)
        else:
            self.cache.put(digest, principal, generation)
        return principal

    def _look_up(self, digest: str, looks_like_user: bool) -> Principal | None:
        with Session(self.engine) as session:
            # The prefix only orders the look-ups: a provisioned token may have any form.
            if looks_like_user:
                return self._user_principal(session, digest) or self._agent_principal(
                    session, digest
                )
            return self._agent_principal(session, digest) or self._user_principal(session, digest)

    def agent_tokens(self, vehicle_id: str | None = None) -> Sequence[AgentTokenRow]:
        query = select(AgentTokenRow).order_by(AgentTokenRow.id)
        if vehicle_id is not None:
            query = query.where(AgentTokenRow.vehicle_id == vehicle_id)
        with Session(self.engine) as session:
            return session.scalars(query).all()

    def revoke_agent_token(self, token_id: int) -> AgentTokenRow:
        self.cache.revoke(lambda who: who.is_agent and who.token_id == token_id)
        with Session(self.engine, expire_on_commit=False) as session, session.begin():
            row = session.get(AgentTokenRow, token_id)
            if row is None:
                raise NotFound(f"no agent token {token_id}")
            row.revoked_at = row.revoked_at or time.time()
        return row


def _live_principal(token_row: UserTokenRow, user: UserRow) -> Principal | None:
    """The principal a user token stands for, or None if the token is revoked or expired
    or its user disabled."""
    if token_row.revoked_at is not None or user.disabled:
        return None
    if token_row.expires_at is not None and token_row.expires_at <= time.time():
        return None
    return user_principal(
        user.username,
        Role(user.role),
        _parse_scopes(token_row.scopes),
        token_row.id,
        token_row.expires_at,
        token_kind=token_row.kind,
        token_name=token_row.name,
    )
