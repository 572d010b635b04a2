"""Prometheus metrics (backend/observability/metrics.py) at ``/metrics``.

Who may read them: a bearer token with the ``admin`` permission, as for every other
operator-only route (a Prometheus scrape job sends one with ``authorization:
credentials_file``). Not loopback-open: behind a reverse proxy on the same machine every
request comes from loopback, and the figures (vehicle counts, rates) are the operator's.

The per-vehicle series (``gcs_vehicle_*{vehicle}``) are read from this hub's registry at
each scrape rather than kept in the process-wide registry: a vehicle no longer in the
registry has no series, and the number of series is bounded by MAX_VEHICLE_SERIES
vehicles (connected ones first, then by id); ``gcs_vehicle_series_omitted`` counts the
vehicles beyond it.
"""

from __future__ import annotations

import time
from collections.abc import Iterator

from fastapi import Response
from prometheus_client import CONTENT_TYPE_LATEST, CollectorRegistry, generate_latest
from prometheus_client.core import GaugeMetricFamily
from prometheus_client.registry import Collector

from backend.api.deps import ClientFeedsDep, RegistryDep, WriterDep
from backend.api.security import SecuredRouter, requires
from backend.auth.policy import Permission
from backend.fleet.registry import FleetRegistry, VehicleRecord
from backend.observability import metrics
from backend.realtime.client_feed import ClientFeed
from backend.storage.writer import StorageWriter

router = SecuredRouter(tags=["system"])

# The most vehicles given series of their own: 6 series each, so at most 3,000 series.
MAX_VEHICLE_SERIES = 500


@router.get(
    "/metrics",
    openapi_extra=requires(Permission.ADMIN),
    response_class=Response,
    # For Prometheus, not for API clients: outside the API document (and the dashboard's
    # types generated from it).
    include_in_schema=False,
)
async def prometheus_metrics(
    registry: RegistryDep, writer: WriterDep, feeds: ClientFeedsDep
) -> Response:
    """The hub's counters and gauges in Prometheus's text format."""
    # Depths are read now rather than kept up to date on every message.
    metrics.QUEUE_DEPTH.labels(queue="storage").set(writer.backlog)
    metrics.QUEUE_DEPTH.labels(queue="dashboard_max").set(
        max(
            (feed.pending for feed in feeds if isinstance(feed, ClientFeed)),
            default=0,
        )
    )
    per_vehicle = CollectorRegistry(auto_describe=False)
    per_vehicle.register(VehicleSeries(registry, writer))
    body = generate_latest() + generate_latest(per_vehicle)
    return Response(body, media_type=CONTENT_TYPE_LATEST)


class VehicleSeries(Collector):
    """Each vehicle's link, freshness, battery, telemetry rate and storage lag, now."""

    def __init__(self, registry: FleetRegistry, writer: StorageWriter) -> None:
        self._registry = registry
        self._writer = writer

    def collect(self) -> Iterator[GaugeMetricFamily]:
        labels = ["vehicle"]
        link = GaugeMetricFamily(
            "gcs_vehicle_link_up",
            "1 while the vehicle's agent is connected, else 0.",
            labels=labels,
        )
        age = GaugeMetricFamily(
            "gcs_vehicle_seconds_since_sample",
            "Seconds since the vehicle's newest telemetry sample (its own clock's stamp).",
            labels=labels,
        )
        percent = GaugeMetricFamily(
            "gcs_vehicle_battery_percent",
            "Battery remaining, percent, as the autopilot reports it (absent if unknown).",
            labels=labels,
        )
        volts = GaugeMetricFamily(
            "gcs_vehicle_battery_volts",
            "Battery voltage, as the autopilot reports it (absent if unknown).",
            labels=labels,
        )
        rate = GaugeMetricFamily(
            "gcs_vehicle_telemetry_rate_hz",
            "New telemetry samples per second from the vehicle's agent over the last 5 s "
            "(a backlog replayed or resent is not counted).",
            labels=labels,
        )
        lag = GaugeMetricFamily(
            "gcs_vehicle_write_lag_seconds",
            "Age of the vehicle's oldest sample in the last batch of its samples the storage "
            "writer committed, at the commit.",
            labels=labels,
        )
        vehicles = self._registry.all()
        # Connected vehicles first (what an operator watches), then by id: stable order.
        shown = sorted(vehicles, key=lambda record: (not record.connected, record.id))
        shown = shown[:MAX_VEHICLE_SERIES]
        now, monotonic = time.time(), time.monotonic()
        for record in shown:
            add_vehicle(record, now, monotonic, link, age, percent, volts, rate)
            if (written := self._writer.vehicle_lag_s.get(record.id)) is not None:
                lag.add_metric([record.id], written)
        omitted = GaugeMetricFamily(
            "gcs_vehicle_series_omitted",
            f"Vehicles in the registry beyond the {MAX_VEHICLE_SERIES} given series of their own.",
            value=len(vehicles) - len(shown),
        )
        yield from (link, age, percent, volts, rate, lag, omitted)


def add_vehicle(
    record: VehicleRecord,
    now: float,
    monotonic: float,
    link: GaugeMetricFamily,
    age: GaugeMetricFamily,
    percent: GaugeMetricFamily,
    volts: GaugeMetricFamily,
    rate: GaugeMetricFamily,
) -> None:
    label = [record.id]
    link.add_metric(label, 1.0 if record.connected else 0.0)
    rate.add_metric(label, record.telemetry_rate(monotonic))
    if record.last_seen is not None:
        age.add_metric(label, max(0.0, now - record.last_seen))
    state = record.state
    if state is not None and state.battery_remaining is not None:
        percent.add_metric(label, state.battery_remaining)
    if state is not None and state.battery_voltage is not None:
        volts.add_metric(label, state.battery_voltage)
