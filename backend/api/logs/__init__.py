"""The flight log's routes, one module per job: the telemetry series, flights, exports,
the event and command history, on-board .tlogs and the storage metrics."""

from __future__ import annotations

from backend.api.logs import exports, flights, history, metrics, series, tlogs

# Each has its own `router`; in this order the OpenAPI document keeps the routes' order.
ROUTE_MODULES = (series, flights, exports, history, tlogs, metrics)

__all__ = ["ROUTE_MODULES"]
