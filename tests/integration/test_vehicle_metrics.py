"""Per-vehicle series on /metrics, scraped from a hub with simulated vehicles flying, and
the Grafana dashboard in deploy/ that reads them."""

from __future__ import annotations

import json
import re
from pathlib import Path

import httpx
import pytest

from gcs.launcher import LocalFleet
from tests.support.waiting import poll_until

pytestmark = pytest.mark.integration

DASHBOARD = Path(__file__).parents[2] / "deploy" / "grafana" / "gcs-fleet.json"
SAMPLE = re.compile(r"^(?P<name>\w+)(\{(?P<labels>[^}]*)\})? (?P<value>\S+)$", re.MULTILINE)


def scrape(fleet: LocalFleet, token: str) -> dict[str, dict[str, float]]:
    """Each series on /metrics: name -> {labels as written: value}."""
    answer = httpx.get(
        f"{fleet.plan.hub_http}/metrics", headers={"Authorization": f"Bearer {token}"}
    )
    assert answer.status_code == 200, answer.text
    series: dict[str, dict[str, float]] = {}
    for match in SAMPLE.finditer(answer.text):
        series.setdefault(match["name"], {})[match["labels"] or ""] = float(match["value"])
    return series


def per_vehicle(series: dict[str, dict[str, float]], name: str) -> dict[str, float]:
    found = series.get(name, {})
    return {labels.split('"')[1]: value for labels, value in found.items()}


def test_each_vehicle_has_its_link_freshness_battery_rate_and_lag(
    fleet: LocalFleet, fleet_admin_token: str
) -> None:
    vehicles = {fleet.vehicle_id(index) for index in range(fleet.plan.vehicles)}

    def every_series() -> dict[str, dict[str, float]] | None:
        series = scrape(fleet, fleet_admin_token)
        # The rate needs a full window of frames, the lag a committed batch.
        rates = per_vehicle(series, "gcs_vehicle_telemetry_rate_hz")
        lags = per_vehicle(series, "gcs_vehicle_write_lag_seconds")
        if vehicles <= set(lags) and all(rates.get(v, 0) >= 5 for v in vehicles):
            return series
        return None

    series = poll_until(every_series, 60, "every vehicle's series")
    assert set(per_vehicle(series, "gcs_vehicle_link_up")) >= vehicles
    for vehicle in vehicles:
        assert per_vehicle(series, "gcs_vehicle_link_up")[vehicle] == 1
        # The agents send 10 frames a second.
        assert 5 <= per_vehicle(series, "gcs_vehicle_telemetry_rate_hz")[vehicle] <= 15, series
        assert 0 <= per_vehicle(series, "gcs_vehicle_seconds_since_sample")[vehicle] < 5
        assert 0 < per_vehicle(series, "gcs_vehicle_battery_percent")[vehicle] <= 100
        assert 10 < per_vehicle(series, "gcs_vehicle_battery_volts")[vehicle] < 30  # a 4S..6S pack
        assert 0 <= per_vehicle(series, "gcs_vehicle_write_lag_seconds")[vehicle] < 10
    assert series["gcs_vehicle_series_omitted"][""] == 0


def test_every_metric_the_dashboard_queries_is_on_metrics(
    fleet: LocalFleet, fleet_admin_token: str
) -> None:
    dashboard = json.loads(DASHBOARD.read_text())
    expressions = [
        target["expr"]
        for panel in dashboard["panels"]
        for target in panel.get("targets", [])
        if "expr" in target
    ]
    assert len(expressions) >= 6
    queried = {
        name
        for expression in expressions
        for name in re.findall(r"\b(gcs_\w+|process_\w+)\b", expression)
    }
    assert {"gcs_vehicle_link_up", "gcs_vehicle_telemetry_rate_hz"} <= queried
    on_metrics = set(scrape(fleet, fleet_admin_token))
    assert queried <= on_metrics, sorted(queried - on_metrics)
    # The vehicle picker reads the vehicle label of a series that exists.
    [variable] = [v for v in dashboard["templating"]["list"] if v["name"] == "vehicle"]
    assert "gcs_vehicle_link_up" in json.dumps(variable["query"])
