"""The per-vehicle series on /metrics are read from the hub's registry at each scrape:
bounded by MAX_VEHICLE_SERIES, connected vehicles first, the rest counted."""

from __future__ import annotations

from dataclasses import dataclass
from types import SimpleNamespace
from typing import Any

import pytest
from prometheus_client import CollectorRegistry, generate_latest

from backend.api import metrics as metrics_route
from backend.fleet.registry import RATE_WINDOW_S, FleetRegistry


@dataclass
class Row:
    """A vehicle as the database remembers it (registry.load takes these)."""

    id: str
    autopilot: str = "ardupilot"
    vehicle_type: str = "multirotor"
    modes: str = "GUIDED,LAND"
    system_id: int = 1
    last_seen: float = 0.0


def scrape(fleet: FleetRegistry, writer: Any) -> str:
    registry = CollectorRegistry(auto_describe=False)
    registry.register(metrics_route.VehicleSeries(fleet, writer))
    return generate_latest(registry).decode()


def test_only_vehicles_in_the_registry_and_at_most_the_cap(monkeypatch: pytest.MonkeyPatch) -> None:
    registry = FleetRegistry()
    registry.load([Row("a"), Row("b"), Row("c")])
    registry.get("c").channel = SimpleNamespace()  # type: ignore[assignment]  # c is online
    writer = SimpleNamespace(vehicle_lag_s={"zz": 1.0})
    monkeypatch.setattr(metrics_route, "MAX_VEHICLE_SERIES", 2)
    text = scrape(registry, writer)
    # The connected vehicle first, then by id; the third is counted, not shown.
    assert 'gcs_vehicle_link_up{vehicle="c"} 1.0' in text
    assert 'gcs_vehicle_link_up{vehicle="a"} 0.0' in text
    assert 'vehicle="b"' not in text
    assert "gcs_vehicle_series_omitted 1.0" in text
    # A vehicle the registry does not hold has no series, whatever else remembers it.
    assert 'vehicle="zz"' not in text


def test_the_rate_counts_the_last_window_only() -> None:
    registry = FleetRegistry()
    registry.load([Row("a")])
    record = registry.get("a")
    for tenth in range(100):  # 10 s of frames at 10 Hz
        record.count_frame(1000.0 + tenth / 10)
    # Frames after 1005.0 (1005.1 to 1009.9): 49 in 5 s.
    assert record.telemetry_rate(1010.0) == pytest.approx(49 / RATE_WINDOW_S)
    assert record.telemetry_rate(1100.0) == 0
