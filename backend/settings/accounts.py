"""Accounts and credentials: the first admin, agents' enrolment tokens, sessions, and the
bounds on logins, password checks and each user's commands."""

from __future__ import annotations

from typing import Literal

from pydantic import BaseModel, Field, SecretStr


class AccountSettings(BaseModel):
    """The first admin, provisioned agent tokens, sessions and the costs of passwords."""

    admin_username: str = Field(
        default="admin",
        pattern=r"^[A-Za-z0-9_.@-]{1,64}$",
        description="name of the first admin, created when there are no users",
    )
    admin_password: SecretStr | None = Field(
        default=None, description="password of the first admin; generated and printed if unset"
    )
    agent_tokens: SecretStr | None = Field(
        default=None,
        description="vehicle=token pairs, comma-separated, enrolled at start (provisioning)",
    )
    session_ttl_s: float = Field(default=12 * 3600, gt=0)
    access_token_ttl_s: float = Field(default=3600, gt=0)

    login_attempts_per_minute: int = Field(
        default=5, ge=1, description="failed logins per address and user name together"
    )
    login_attempts_per_address_per_minute: int = Field(
        default=20, ge=1, description="failed logins per address, whatever the user name"
    )
    password_hash_threads: int = Field(
        default=2, ge=1, le=32, description="threads of their own for argon2 (64 MB each)"
    )
    # backend.auth.secrets.PasswordCost's names (mypy checks them where the hub hands this
    # to its accounts): said here so that the settings need nothing of auth.
    password_hash_cost: Literal["standard", "test"] = Field(
        default="standard",
        description="argon2's cost: 'test' is its least, for the test suite only "
        "(refused in production)",
    )
    password_hash_max_pending: int = Field(
        default=8, ge=1, description="password checks running or waiting; beyond, 429"
    )
    commands_per_second: int = Field(
        default=20,
        ge=1,
        description="requests that reach a vehicle, per user (commands, parameters, missions)",
    )

    principal_cache_s: float = Field(
        default=10.0, ge=0, le=300, description="a resolved token answers without the database"
    )
    principal_cache_outage_s: float = Field(
        default=3600.0, ge=0, description="a resolved token answers while the database is down"
    )
    audit_denial_interval_s: float = Field(
        default=60.0,
        gt=0,
        le=3600,
        description="refused requests of one principal, route and reason within this are "
        "one audit row and then one more with their count",
    )

    def enrolment_tokens(self) -> dict[str, str]:
        """The provisioned ``vehicle=token`` pairs."""
        if self.agent_tokens is None:
            return {}
        pairs = {}
        for item in self.agent_tokens.get_secret_value().split(","):
            vehicle, separator, token = item.strip().partition("=")
            if not separator or not vehicle or not token:
                raise ValueError("GCS_AGENT_TOKENS must be vehicle=token pairs, comma-separated")
            pairs[vehicle] = token
        return pairs
