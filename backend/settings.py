"""The hub's one settings class, loaded from the environment (GCS_*) and validated at start."""

from __future__ import annotations

from pathlib import Path

from pydantic import AliasChoices, Field, SecretStr
from pydantic_settings import BaseSettings, SettingsConfigDict

from gcs.protocol import MAX_FRAME_BYTES

REPO_ROOT = Path(__file__).resolve().parent.parent


class HubSettings(BaseSettings):
    model_config = SettingsConfigDict(env_prefix="GCS_", extra="ignore")

    host: str = "127.0.0.1"
    port: int = Field(default=8000, ge=0, le=65535)
    data_dir: Path = Field(default=Path("data"), description="SQLite file and logs live here")
    database_url: str | None = Field(
        default=None,
        validation_alias=AliasChoices("DATABASE_URL", "GCS_DATABASE_URL"),
        description="SQLAlchemy URL; SQLite in the data folder when unset",
    )
    agent_token: SecretStr = Field(description="token every agent must present (v1: shared)")

    command_timeout_s: float = Field(default=15.0, gt=0, le=120)
    telemetry_batch_size: int = Field(default=500, ge=1)
    telemetry_flush_interval_s: float = Field(default=0.25, gt=0)
    telemetry_queue_limit: int = Field(default=20_000, ge=100)
    ui_update_interval_s: float = Field(default=0.1, gt=0, description="per-client coalescing")
    max_frame_bytes: int = Field(default=MAX_FRAME_BYTES, ge=1024)
    max_bad_frames: int = Field(default=20, ge=1, description="before a connection is closed")

    basemap_url: str | None = Field(
        default=None, description="XYZ tile URL template; a plain grid when unset (offline)"
    )
    basemap_attribution: str = ""
    basemap_max_zoom: int = Field(default=19, ge=1, le=24)
    frontend_dir: Path = REPO_ROOT / "frontend" / "dist"

    @property
    def sqlalchemy_url(self) -> str:
        if self.database_url:
            return self.database_url
        return f"sqlite:///{(self.data_dir / 'gcs.sqlite3').resolve()}"
