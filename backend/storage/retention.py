"""How long each table keeps its rows."""

from __future__ import annotations

from dataclasses import dataclass

# The database itself refuses to delete audit entries younger than this (migration 0004),
# so no setting, bug or stolen connection can shorten the audit trail below it.
AUDIT_MIN_RETENTION_DAYS = 30


@dataclass(frozen=True)
class RetentionPolicy:
    """Days to keep each table's rows; None keeps them for ever."""

    telemetry_days: float | None = None
    events_days: float | None = None
    commands_days: float | None = None
    flights_days: float | None = None
    audit_days: float | None = None
