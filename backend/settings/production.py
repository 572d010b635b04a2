"""What a hub refuses to start with: default secrets and the test suite's password cost in
production, a development hub reachable from the network; and the secrets read from files.

The strength of the first admin's password is the account policy's to judge
(`backend.auth.password_policy`), where the hub creates that admin (`backend.hub`): the
settings know only the defaults that ship in examples, so they need nothing of auth."""

from __future__ import annotations

import os
from pathlib import Path
from typing import TYPE_CHECKING, Any
from urllib.parse import urlsplit

if TYPE_CHECKING:
    from backend.settings.hub_settings import HubSettings

# Secrets that ship in examples and tutorials; refused outside development.
WEAK_SECRETS = frozenset(
    {"", "admin", "password", "changeme", "change-me", "secret", "gcs", "postgres", "test"}
)
SECRET_FILE_VARIABLES = {
    "GCS_ADMIN_PASSWORD_FILE": "admin_password",
    "DATABASE_URL_FILE": "database_url",
    "GCS_AGENT_TOKENS_FILE": "agent_tokens",
    "GCS_BUS_PASSWORD_FILE": "bus_password",
}


def with_secret_files(values: Any) -> Any:
    """``X_FILE`` variables name files holding secrets (Docker and systemd credentials)."""
    if not isinstance(values, dict):
        return values
    for variable, field_name in SECRET_FILE_VARIABLES.items():
        path = os.environ.get(variable)
        if path and field_name not in values:
            values[field_name] = Path(path).read_text().strip()
    return values


def refuse_unsafe(settings: HubSettings) -> None:
    """Raise ValueError naming every default secret of a production hub, or a development
    hub's exposure to the network."""
    if settings.fleet_speedup != 1.0 and settings.environment != "development":
        # a real aircraft asked to fly a route four times as fast as planned
        raise ValueError("GCS_FLEET_SPEEDUP is for simulated fleets, in development only")
    if settings.environment == "development":
        if not settings.on_loopback and not settings.allow_development_on_network:
            raise ValueError(
                f"refusing to listen on {settings.host} in development mode, where default "
                "passwords, short agent tokens and plain-HTTP cookies pass: anyone who "
                "can reach the port could take the fleet. Use GCS_ENVIRONMENT=production, "
                "or set GCS_ALLOW_DEVELOPMENT_ON_NETWORK=true on a network you trust"
            )
        return
    problems = []
    if settings.password_hash_cost != "standard":
        problems.append("GCS_PASSWORD_HASH_COST is only for the test suite")
    admin_password = settings.admin_password
    if admin_password is not None and admin_password.get_secret_value().lower() in WEAK_SECRETS:
        problems.append("GCS_ADMIN_PASSWORD is a default")
    if settings.database_url:
        db_password = urlsplit(settings.database_url).password
        if db_password is not None and db_password.lower() in WEAK_SECRETS:
            problems.append("DATABASE_URL uses a default password")
    for vehicle, token in settings.enrolment_tokens().items():
        if len(token) < 24:
            problems.append(f"the agent token for {vehicle} is shorter than 24 characters")
    if settings.bus_url is not None:
        problems += settings.bus_credential_problems()
    if problems:
        raise ValueError(
            "refusing default secrets in production (set GCS_ENVIRONMENT=development "
            "for a local trial): " + "; ".join(problems)
        )
