"""Where the hub listens and keeps its data, and the bounds on what one HTTP client may hold."""

from __future__ import annotations

from pathlib import Path
from typing import Literal

from pydantic import AliasChoices, BaseModel, Field

from common.addresses import is_loopback

# The checkout the hub runs from (this file is backend/settings/server.py).
REPO_ROOT = Path(__file__).resolve().parents[2]


class ServerSettings(BaseModel):
    """The listening socket, the store and the folders, HTTP's limits, the log format."""

    host: str = "127.0.0.1"
    port: int = Field(default=8000, ge=0, le=65535)
    data_dir: Path = Field(default=Path("data"), description="SQLite file and logs live here")
    database_url: str | None = Field(
        default=None,
        validation_alias=AliasChoices("DATABASE_URL", "GCS_DATABASE_URL"),
        description="SQLAlchemy URL; SQLite in the data folder when unset",
    )
    environment: Literal["development", "production"] = Field(
        default="production", description="development relaxes cookie and secret checks"
    )
    allow_development_on_network: bool = Field(
        default=False,
        description="let a development hub listen beyond loopback (a trusted field LAN)",
    )

    cors_origins: list[str] = Field(default_factory=list)
    forwarded_allow_ips: str = Field(
        default="127.0.0.1",
        description="proxies whose X-Forwarded-For is believed: the default assumes a proxy "
        "on the same host; without a proxy it must be empty",
    )
    max_body_bytes: int = Field(default=1024 * 1024, ge=1024)
    max_tlog_bytes: int = Field(default=512 * 1024 * 1024, ge=1024, description="per upload")
    # Slow clients (see docs/security.md "Limits in force"): a body must come within
    # body_timeout_s plus a second per body_min_rate_bps bytes; idle keep-alive
    # connections close after keep_alive_timeout_s; past max_connections, new requests
    # get 503.
    body_timeout_s: float = Field(default=10.0, gt=0)
    body_min_rate_bps: float = Field(default=1024.0, gt=0)
    keep_alive_timeout_s: int = Field(default=5, ge=1)
    shutdown_grace_s: int = Field(
        default=5,
        ge=1,
        le=60,
        description="on SIGTERM, how long requests in progress (a survey plan, an export) "
        "may run on before they are cancelled and the hub stops",
    )
    max_connections: int = Field(default=1000, ge=1)
    max_tlog_bytes_per_vehicle: int = Field(
        default=4 * 1024 * 1024 * 1024,
        ge=1024,
        description="all of one vehicle's stored .tlogs together; an upload beyond is a 413",
    )

    log_format: Literal["text", "json"] = Field(
        default="text", description="json: one JSON object a line (time, level, logger, message)"
    )

    spool_retry_s: float = Field(
        default=2.0, gt=0, description="retry storing spooled audit and command rows"
    )

    spool_dir: Path | None = Field(
        default=None,
        description="the spool of audit and command rows kept through a database outage; "
        "<data dir> when unset. Hubs that share a data folder need one each",
    )
    tiles_dir: Path | None = Field(
        default=None, description="offline tile sets (.mbtiles, .pmtiles); <data dir>/tiles"
    )
    param_metadata_dir: Path | None = Field(
        default=None,
        description="ArduPilot's parameter metadata, as ArduPilot publishes it: "
        "<dir>/ArduCopter/apm.pdef.json (ArduPlane, Rover, ArduSub alike); a write outside a "
        "parameter's range or values is refused. Unset or missing: ArduPilot writes are not "
        "range-checked (PX4 vehicles serve their own metadata)",
    )
    frontend_dir: Path | None = Field(
        default=None,
        description="the built dashboard (its index.html); unset: frontend/dist of the "
        "checkout the hub runs from. A hub installed from a wheel has no checkout: set it",
    )

    @property
    def photos_folder(self) -> Path:
        return self.data_dir / "photos"

    @property
    def spool_file(self) -> Path:
        return (self.spool_dir or self.data_dir) / "spool.jsonl"

    @property
    def tiles_folder(self) -> Path:
        return self.tiles_dir or self.data_dir / "tiles"

    @property
    def on_loopback(self) -> bool:
        """Listening on this machine only, where nothing else on the network reaches."""
        return is_loopback(self.host)

    @property
    def cookie_secure(self) -> bool:
        """Secure cookies need HTTPS; a local development hub serves plain HTTP."""
        return self.environment == "production"

    @property
    def sqlalchemy_url(self) -> str:
        if self.database_url:
            return self.database_url
        return f"sqlite:///{(self.data_dir / 'gcs.sqlite3').resolve()}"
