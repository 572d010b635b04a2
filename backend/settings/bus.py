"""Several hubs: the NATS bus between them and its credentials."""

from __future__ import annotations

from pathlib import Path
from typing import Self
from urllib.parse import urlsplit

from pydantic import BaseModel, Field, SecretStr, model_validator

from backend.settings.production import WEAK_SECRETS


class BusSettings(BaseModel):
    """The NATS bus; unset, the hub is alone and its bus is in-process."""

    # Several hubs (docs/deployer.md "Several hubs"): a NATS server joins them; unset, the hub is
    # alone and its bus is in-process (the embedded default).
    bus_url: str | None = Field(
        default=None,
        description="NATS URL (nats://host:4222) shared by several hubs; unset: one hub, "
        "in-process bus",
    )
    bus_prefix: str = Field(
        default="gcs",
        pattern=r"^[A-Za-z0-9_-]{1,64}$",
        description="first token of every NATS subject, so deployments can share a server",
    )
    bus_request_timeout_s: float = Field(
        default=2.0, gt=0, le=30, description="a routed command's extra time on the bus"
    )
    # The hubs' NATS credentials: a user and password (or nats://user:password@host in
    # bus_url), or an NKey/JWT credentials file. Outside development a bus without
    # credentials is refused at start: any client on the bus could command the fleet.
    bus_user: str | None = Field(default=None, max_length=256, description="NATS user")
    bus_password: SecretStr | None = Field(
        default=None, description="NATS password (or GCS_BUS_PASSWORD_FILE)"
    )
    bus_creds_file: Path | None = Field(
        default=None, description="NATS credentials file (NKey seed and user JWT)"
    )
    bus_tls_ca_file: Path | None = Field(
        default=None, description="CA that signed the NATS server's certificate: TLS to the bus"
    )

    def bus_credential_problems(self) -> list[str]:
        """Why the hub's NATS credentials are missing or a default (refused in production)."""
        if not self.bus_has_credentials:
            return [
                f"GCS_BUS_URL {redacted_url(self.bus_url or '')} carries no credentials: set "
                "GCS_BUS_USER and GCS_BUS_PASSWORD (or GCS_BUS_PASSWORD_FILE), "
                "GCS_BUS_CREDS_FILE, or nats://user:password@host in GCS_BUS_URL; without "
                "them any client that reaches the NATS server can command the fleet"
            ]
        if self.bus_password is not None:
            password: str | None = self.bus_password.get_secret_value()
        else:
            password = urlsplit(self.bus_url or "").password
        if password is not None and password.lower() in WEAK_SECRETS:
            return ["GCS_BUS_PASSWORD is a default"]
        return []

    @model_validator(mode="after")
    def _bus_user_with_password(self) -> Self:
        if (self.bus_user is None) != (self.bus_password is None):
            raise ValueError("GCS_BUS_USER and GCS_BUS_PASSWORD go together: set both or neither")
        return self

    @property
    def bus_has_credentials(self) -> bool:
        """The hub presents credentials to NATS (a user or token in the URL counts)."""
        in_url = self.bus_url is not None and urlsplit(self.bus_url).username
        return bool(self.bus_user or self.bus_creds_file or in_url)


def redacted_url(url: str) -> str:
    """A URL as the logs may show it: its password (or token) replaced by ***."""
    parts = urlsplit(url)
    if parts.username is None and parts.password is None:
        return url
    host = parts.hostname or ""
    if parts.port is not None:
        host = f"{host}:{parts.port}"
    who = "***" if parts.password is None else f"{parts.username}:***"
    return parts._replace(netloc=f"{who}@{host}").geturl()
