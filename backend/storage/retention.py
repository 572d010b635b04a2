"""How long each table keeps its rows."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class RetentionPolicy:
    """Days to keep each table's rows; None keeps them for ever."""

    telemetry_days: float | None = None
    events_days: float | None = None
    commands_days: float | None = None
    flights_days: float | None = None
