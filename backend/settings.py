"""The hub's one settings class, loaded from the environment (GCS_*) and validated at start."""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any, Literal
from urllib.parse import urlsplit

from pydantic import AliasChoices, Field, SecretStr, model_validator
from pydantic_settings import BaseSettings, SettingsConfigDict

from backend.auth.password_policy import password_problem
from backend.auth.secrets import PasswordCost
from backend.storage.retention import AUDIT_MIN_RETENTION_DAYS, RetentionPolicy
from common.addresses import is_loopback
from common.geodesy import LocalFrame
from protocol.messages import MAX_FRAME_BYTES, MAX_MISSION_ITEMS

REPO_ROOT = Path(__file__).resolve().parent.parent
OSM_TILE_URL = "https://tile.openstreetmap.org/{z}/{x}/{y}.png"
OSM_ATTRIBUTION = (
    '&copy; <a href="https://www.openstreetmap.org/copyright">OpenStreetMap</a> contributors'
)

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


class HubSettings(BaseSettings):
    model_config = SettingsConfigDict(env_prefix="GCS_", extra="ignore", hide_input_in_errors=True)

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
    cors_origins: list[str] = Field(default_factory=list)
    forwarded_allow_ips: str = Field(
        default="127.0.0.1",
        description="proxies whose X-Forwarded-For is believed: the default assumes a proxy "
        "on the same host; without a proxy it must be empty",
    )
    max_body_bytes: int = Field(default=1024 * 1024, ge=1024)
    max_tlog_bytes: int = Field(default=512 * 1024 * 1024, ge=1024, description="per upload")
    # Slow clients (see README "Limits"): a body must come within body_timeout_s plus a
    # second per body_min_rate_bps bytes; idle keep-alive connections close after
    # keep_alive_timeout_s; past max_connections, new requests get 503.
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
    login_attempts_per_minute: int = Field(
        default=5, ge=1, description="failed logins per address and user name together"
    )
    login_attempts_per_address_per_minute: int = Field(
        default=20, ge=1, description="failed logins per address, whatever the user name"
    )
    password_hash_threads: int = Field(
        default=2, ge=1, le=32, description="threads of their own for argon2 (64 MB each)"
    )
    password_hash_cost: PasswordCost = Field(
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

    max_altitude_m: float | None = Field(default=120.0, description="site ceiling above home")
    min_altitude_m: float | None = Field(default=None, description="site floor for targets")
    max_distance_from_home_m: float | None = Field(default=2000.0)
    min_launch_battery_pct: float | None = Field(default=30.0)
    battery_reserve_pct: float = Field(default=20.0, ge=0, le=100)
    min_height_above_home_m: float | None = Field(
        default=2.0, ge=0, description="lowest a mission's navigation items go but landings"
    )

    command_timeout_s: float = Field(default=15.0, gt=0, le=120)
    formation_join_timeout_s: float = Field(
        default=60.0,
        gt=0,
        le=3600,
        description="a formation whose followers are not all in their slots this long "
        "after its start ends, and every member holds",
    )
    fleet_speedup: float = Field(
        default=1.0,
        ge=1.0,
        le=100.0,
        description="a simulated fleet's speed-up (the simulators' --speedup, one for the "
        "fleet): formations fly their routes in the vehicles' seconds; 1 for aircraft, and "
        "only in development",
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
    spool_retry_s: float = Field(
        default=2.0, gt=0, description="retry storing spooled audit and command rows"
    )
    telemetry_batch_size: int = Field(default=500, ge=1)
    telemetry_flush_interval_s: float = Field(default=0.25, gt=0)
    telemetry_queue_limit: int = Field(default=20_000, ge=100)
    ui_update_interval_s: float = Field(
        default=0.1, gt=0, description="per-client pacing of live event batches"
    )
    ui_vehicle_interval_s: float = Field(
        default=0.05,
        gt=0,
        description="the least time between two updates of one vehicle to the client feeds",
    )
    ui_batch_interval_s: float = Field(
        default=0.01, gt=0, description="the least time between two vehicle batches to a feed"
    )
    log_format: Literal["text", "json"] = Field(
        default="text", description="json: one JSON object a line (time, level, logger, message)"
    )
    slow_client_timeout_s: float = Field(
        default=10.0,
        gt=0,
        description="a client feed that takes no vehicle batch for this long is closed (4408)",
    )
    max_frame_bytes: int = Field(default=MAX_FRAME_BYTES, ge=1024)
    viz_enabled: bool = Field(default=True, description="serve the 3D view (viser) at /viz/")
    viz_origin: str | None = Field(
        default=None,
        pattern=r"^\s*-?[0-9.]+\s*,\s*-?[0-9.]+\s*(,\s*-?[0-9.]+\s*)?$",
        description="'lat,lon[,alt_msl]' of the 3D view's local east-north-up origin; "
        "the first home position the fleet reports when unset",
    )
    viz_update_interval_s: float = Field(
        default=0.1, ge=0.02, le=5.0, description="the 3D scene's batched update period"
    )
    viz_trail_s: float = Field(default=60.0, ge=0, le=3600, description="3D trail length")
    max_bad_frames: int = Field(default=20, ge=1, description="before a connection is closed")
    site_origin: str | None = Field(
        default=None,
        pattern=r"^-?\d+(\.\d+)?,-?\d+(\.\d+)?,-?\d+(\.\d+)?$",
        description="LAT,LON,ALT_MSL of the site's east-north-up frame (scans' world points, "
        "the point map); unset: the first scan's position",
    )
    scan_voxel_m: float = Field(
        default=0.1, ge=0.01, le=5.0, description="the point map's voxel size"
    )
    scan_map_max_voxels: int = Field(
        default=500_000,
        ge=1000,
        description="the point map's bound (about 100 bytes each): the least recently seen "
        "voxels go first",
    )
    scan_max_rate_hz: float = Field(
        default=20.0, gt=0, le=100, description="live scans per second per vehicle, at most"
    )
    scan_queue_limit: int = Field(default=2000, ge=10, description="scans waiting to be stored")
    survey_link_timeout_s: float = Field(
        default=10.0,
        gt=0,
        le=3600,
        description="a surveying drone whose agent has been gone this long is out of the "
        "survey: its unflown lanes are offered to the others",
    )
    survey_battery_floor_pct: float = Field(
        default=20.0,
        ge=0,
        le=100,
        description="a surveying drone whose battery falls below this is out of the survey",
    )
    photo_survey_margin_m: float = Field(
        default=500.0,
        gt=0,
        description="a photo whose position is further than this outside its survey's area "
        "is refused (a wrong pose, or a photo of another survey)",
    )
    max_photo_bytes_per_vehicle: int = Field(
        default=20 * 1024 * 1024 * 1024,
        ge=1024,
        description="all of one vehicle's stored photos and the declared sizes of its "
        "uploads in progress together; an upload beyond is a 413",
    )
    photo_uploads_per_vehicle: int = Field(
        default=8,
        ge=1,
        le=64,
        description="photo uploads one vehicle may have in progress at once; beyond, 429",
    )
    photo_upload_expiry_s: float = Field(
        default=6 * 3600.0,
        ge=60,
        description="an unfinished photo upload untouched this long is removed",
    )
    survey_update_interval_s: float = Field(
        default=1.0, gt=0, le=60, description="a survey's progress goes out at most this often"
    )
    # Survey planning's bounds (docs/security.md "Survey planning"): a plan is estimated
    # from the area and the camera before it is planned, and refused (422) past these.
    survey_max_lanes: int = Field(
        default=1000, ge=1, description="lanes a survey plan may have (estimated first)"
    )
    survey_max_photos: int = Field(
        default=20_000, ge=1, description="photos a survey plan may take (estimated first)"
    )
    survey_max_mission_items: int = Field(
        default=700,
        ge=10,
        le=MAX_MISSION_ITEMS,
        description="items one drone's survey mission may have: the smallest mission store "
        "in the fleet (ArduPilot on a 16 KB FRAM board holds about 700; an SD card far more)",
    )
    survey_plan_timeout_s: float = Field(
        default=30.0, gt=0, le=600, description="a survey plan still running after this stops"
    )
    survey_plan_workers: int = Field(
        default=2, ge=1, le=32, description="survey plans computed at once (worker processes)"
    )
    survey_plan_max_pending: int = Field(
        default=8, ge=1, description="survey plans running or waiting for a worker; beyond, 429"
    )
    survey_import_max_bytes: int = Field(
        default=1_000_000, ge=1024, description="a survey area file's size (KML, GeoJSON, .plan)"
    )
    survey_import_max_vertices: int = Field(
        default=10_000, ge=4, description="the vertices of a survey area file's polygon"
    )
    survey_import_max_pending: int = Field(
        default=4, ge=1, description="area files being read or waiting (one worker); beyond, 429"
    )
    survey_import_timeout_s: float = Field(
        default=10.0, gt=0, le=600, description="an area file still being read after this stops"
    )
    survey_imports_per_minute: int = Field(
        default=10, ge=1, description="survey area files one user may import per minute"
    )
    scan_obstacle_interval_s: float = Field(
        default=5.0,
        gt=0,
        description="how often obstacles are extracted from the point map; one found or "
        "gone is an event (kind 'obstacle')",
    )

    def site_frame(self) -> LocalFrame | None:
        """The site's east-north-up frame, if an origin is configured."""
        if self.site_origin is None:
            return None
        lat, lon, alt = (float(part) for part in self.site_origin.split(","))
        return LocalFrame(lat, lon, alt)

    agent_liveness_timeout_s: float = Field(
        default=3.0,
        gt=0,
        le=4.0,  # the newcomer waits this long for its welcome; our agent waits 5 s
        description="a second agent for a vehicle id takes it over only if the first "
        "sends nothing for this long after a ping; otherwise it is refused (close 4409)",
    )

    # Several hubs (README "Several hubs"): a NATS server joins them; unset, the hub is
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

    retention_telemetry_days: float | None = Field(default=None, gt=0)
    retention_events_days: float | None = Field(default=None, gt=0)
    retention_commands_days: float | None = Field(default=None, gt=0)
    retention_flights_days: float | None = Field(default=None, gt=0)
    retention_audit_days: float | None = Field(
        default=365,
        ge=AUDIT_MIN_RETENTION_DAYS,
        description="the database refuses to delete younger audit entries; None keeps all",
    )
    retention_interval_s: float = Field(default=3600, gt=0)

    # The online base maps: XYZ URL templates ({z}/{x}/{y}, optionally {s} for a, b, c).
    # An empty URL turns one off; the CSP lets the browser reach exactly these hosts.
    basemap_url: str | None = Field(
        default=OSM_TILE_URL, description="the street map; empty turns it off"
    )
    basemap_attribution: str = Field(
        default="", description="shown with the street map; OpenStreetMap's for its tiles"
    )
    basemap_max_zoom: int = Field(default=19, ge=1, le=24)
    imagery_url: str | None = Field(default=None, description="aerial imagery; off when unset")
    imagery_attribution: str = ""
    imagery_max_zoom: int = Field(default=19, ge=1, le=24)
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

    @model_validator(mode="before")
    @classmethod
    def _secret_files(cls, values: Any) -> Any:
        """``X_FILE`` variables name files holding secrets (Docker and systemd credentials)."""
        if not isinstance(values, dict):
            return values
        for variable, field_name in SECRET_FILE_VARIABLES.items():
            path = os.environ.get(variable)
            if path and field_name not in values:
                values[field_name] = Path(path).read_text().strip()
        return values

    @model_validator(mode="after")
    def _online_base_maps(self) -> HubSettings:
        for name in ("basemap_url", "imagery_url"):
            url = getattr(self, name)
            if not url:
                setattr(self, name, None)  # empty: this base map is off
                continue
            problem = tile_url_problem(url)
            if problem:
                raise ValueError(f"GCS_{name.upper()} {problem}")
        if self.basemap_url == OSM_TILE_URL and not self.basemap_attribution:
            self.basemap_attribution = OSM_ATTRIBUTION  # its licence asks for it
        return self

    @model_validator(mode="after")
    def _no_default_secrets_in_production(self) -> HubSettings:
        if self.fleet_speedup != 1.0 and self.environment != "development":
            # a real aircraft asked to fly a route four times as fast as planned
            raise ValueError("GCS_FLEET_SPEEDUP is for simulated fleets, in development only")
        if self.environment == "development":
            if not self.on_loopback and not self.allow_development_on_network:
                raise ValueError(
                    f"refusing to listen on {self.host} in development mode, where default "
                    "passwords, short agent tokens and plain-HTTP cookies pass: anyone who "
                    "can reach the port could take the fleet. Use GCS_ENVIRONMENT=production, "
                    "or set GCS_ALLOW_DEVELOPMENT_ON_NETWORK=true on a network you trust"
                )
            return self
        problems = []
        if self.password_hash_cost != "standard":
            problems.append("GCS_PASSWORD_HASH_COST is only for the test suite")
        if self.admin_password is not None:
            password = self.admin_password.get_secret_value()
            weakness = password_problem(password, self.admin_username)
            if password.lower() in WEAK_SECRETS or weakness:
                problems.append(f"GCS_ADMIN_PASSWORD {weakness or 'is a default'}")
        if self.database_url:
            db_password = urlsplit(self.database_url).password
            if db_password is not None and db_password.lower() in WEAK_SECRETS:
                problems.append("DATABASE_URL uses a default password")
        for vehicle, token in self.enrolment_tokens().items():
            if len(token) < 24:
                problems.append(f"the agent token for {vehicle} is shorter than 24 characters")
        if self.bus_url is not None:
            problems += self._bus_credential_problems()
        if problems:
            raise ValueError(
                "refusing default secrets in production (set GCS_ENVIRONMENT=development "
                "for a local trial): " + "; ".join(problems)
            )
        return self

    def _bus_credential_problems(self) -> list[str]:
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
    def _bus_user_with_password(self) -> HubSettings:
        if (self.bus_user is None) != (self.bus_password is None):
            raise ValueError("GCS_BUS_USER and GCS_BUS_PASSWORD go together: set both or neither")
        return self

    @property
    def bus_has_credentials(self) -> bool:
        """The hub presents credentials to NATS (a user or token in the URL counts)."""
        in_url = self.bus_url is not None and urlsplit(self.bus_url).username
        return bool(self.bus_user or self.bus_creds_file or in_url)

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

    def retention_policy(self) -> RetentionPolicy:
        return RetentionPolicy(
            telemetry_days=self.retention_telemetry_days,
            events_days=self.retention_events_days,
            commands_days=self.retention_commands_days,
            flights_days=self.retention_flights_days,
            audit_days=self.retention_audit_days,
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
    def online_tile_urls(self) -> list[str]:
        return [url for url in (self.basemap_url, self.imagery_url) if url]

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


def tile_url_problem(url: str) -> str:
    """Why an XYZ URL template cannot be used, or "" when it can."""
    parts = urlsplit(url)
    if parts.scheme not in ("https", "http") or not parts.netloc:
        return f"must be an http(s) URL, not {url!r}"
    missing = [key for key in ("{z}", "{x}", "{y}") if key not in url]
    if missing:
        return f"must hold {', '.join(missing)} (an XYZ template such as {OSM_TILE_URL})"
    return ""
