"""A Python client for the Fleet GCS hub: its REST API and its live feed, typed.

    from gcs_client import Hub

    async with Hub("http://127.0.0.1:8000", username="admin", password="...") as hub:
        await hub.vehicles.command("sim_1", "takeoff", altitude=10)
        async for vehicle in hub.telemetry():
            print(vehicle.id, vehicle.state.alt_rel if vehicle.state else None)

``SyncHub`` is the same without asyncio. Every error is a ``HubError`` carrying the hub's
reason (``gcs_client.errors``); the models are ``gcs_client.models``, generated from the
hub's OpenAPI document and the wire protocol. See docs/client.md.
"""

from gcs_client.errors import (
    ApiError,
    CommandRefused,
    Conflict,
    FeedClosed,
    Forbidden,
    GatewayTimeout,
    HubError,
    HubUnreachable,
    InvalidCommand,
    MissingCredentials,
    NotFound,
    PayloadTooLarge,
    RateLimited,
    Unauthorized,
    Unavailable,
    Unprocessable,
    WaitTimedOut,
)
from gcs_client.feed import FleetWatch, LiveFeed
from gcs_client.hub import Hub
from gcs_client.sync import SyncHub

__all__ = [
    "ApiError",
    "CommandRefused",
    "Conflict",
    "FeedClosed",
    "FleetWatch",
    "Forbidden",
    "GatewayTimeout",
    "Hub",
    "HubError",
    "HubUnreachable",
    "InvalidCommand",
    "LiveFeed",
    "MissingCredentials",
    "NotFound",
    "PayloadTooLarge",
    "RateLimited",
    "SyncHub",
    "Unauthorized",
    "Unavailable",
    "Unprocessable",
    "WaitTimedOut",
]
