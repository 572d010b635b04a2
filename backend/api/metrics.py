"""Prometheus metrics (backend/observability/metrics.py) at ``/metrics``.

Who may read them: a bearer token with the ``admin`` permission, as for every other
operator-only route (a Prometheus scrape job sends one with ``authorization:
credentials_file``). Not loopback-open: behind a reverse proxy on the same machine every
request comes from loopback, and the figures (vehicle counts, rates) are the operator's.
"""

from __future__ import annotations

from fastapi import Response
from prometheus_client import CONTENT_TYPE_LATEST, generate_latest

from backend.api.deps import HubDep
from backend.api.security import SecuredRouter, requires
from backend.auth.policy import Permission
from backend.observability import metrics
from backend.realtime.client_feed import ClientFeed

router = SecuredRouter(tags=["system"])


@router.get(
    "/metrics",
    openapi_extra=requires(Permission.ADMIN),
    response_class=Response,
    # For Prometheus, not for API clients: outside the API document (and the dashboard's
    # types generated from it).
    include_in_schema=False,
)
async def prometheus_metrics(hub: HubDep) -> Response:
    """The hub's counters and gauges in Prometheus's text format."""
    # Depths are read now rather than kept up to date on every message.
    metrics.QUEUE_DEPTH.labels(queue="storage").set(hub.writer.backlog)
    metrics.QUEUE_DEPTH.labels(queue="dashboard_max").set(
        max(
            (feed.pending for feed in hub.client_feeds if isinstance(feed, ClientFeed)),
            default=0,
        )
    )
    return Response(generate_latest(), media_type=CONTENT_TYPE_LATEST)
