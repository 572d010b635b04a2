"""How long the store keeps each kind of record."""

from __future__ import annotations

from pydantic import BaseModel, Field

from backend.storage.retention import AUDIT_MIN_RETENTION_DAYS, RetentionPolicy


class RetentionSettings(BaseModel):
    """Retention per kind of record, and how often it is applied."""

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

    def retention_policy(self) -> RetentionPolicy:
        return RetentionPolicy(
            telemetry_days=self.retention_telemetry_days,
            events_days=self.retention_events_days,
            commands_days=self.retention_commands_days,
            flights_days=self.retention_flights_days,
            audit_days=self.retention_audit_days,
        )
