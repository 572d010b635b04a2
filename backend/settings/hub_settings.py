"""The hub's one settings class: every group's settings, loaded from the environment
(GCS_*) and validated at start."""

from __future__ import annotations

from typing import Any, Self

from pydantic import model_validator
from pydantic_settings import BaseSettings, SettingsConfigDict

from backend.settings.accounts import AccountSettings
from backend.settings.base_maps import BaseMapSettings
from backend.settings.bus import BusSettings
from backend.settings.live import LiveSettings
from backend.settings.production import refuse_unsafe, with_secret_files
from backend.settings.rails import SafetyRailSettings
from backend.settings.retention import RetentionSettings
from backend.settings.scans import ScanSettings
from backend.settings.server import ServerSettings
from backend.settings.surveys import SurveySettings


class HubSettings(
    ServerSettings,
    AccountSettings,
    SafetyRailSettings,
    LiveSettings,
    ScanSettings,
    SurveySettings,
    BusSettings,
    RetentionSettings,
    BaseMapSettings,
    BaseSettings,
):
    """One flat set of GCS_* variables (each group's fields), checked as a whole: a
    production hub's secrets span the groups."""

    model_config = SettingsConfigDict(env_prefix="GCS_", extra="ignore", hide_input_in_errors=True)

    @model_validator(mode="before")
    @classmethod
    def _secret_files(cls, values: Any) -> Any:
        return with_secret_files(values)

    @model_validator(mode="after")
    def _no_default_secrets_in_production(self) -> Self:
        refuse_unsafe(self)
        return self
