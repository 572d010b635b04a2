"""What every example shares: finding the hub, logging in, and checking each answer.

The examples read their settings from the environment:

    GCS_HUB        the hub's address (default http://127.0.0.1:8000)
    GCS_TOKEN      a bearer token: an API token (POST /api/v1/auth/api-tokens) or an
                   access token; if unset, the examples log in with
    GCS_USERNAME   and
    GCS_PASSWORD   through the OAuth2 password flow (POST /api/v1/auth/token, a form)

Any error answer ends the example with its reason and exit status 1.
"""

from __future__ import annotations

import json
import os
import time
from collections.abc import Callable
from typing import Any

import httpx
import websockets.exceptions
import websockets.sync.client


def hub_address() -> str:
    return os.environ.get("GCS_HUB", "http://127.0.0.1:8000").rstrip("/")


def feed_address() -> str:
    """The live feed's WebSocket address: the hub's, with ws:// for http://."""
    return "ws" + hub_address().removeprefix("http") + "/api/v1/ws"


def check(response: httpx.Response) -> Any:
    """The answer's JSON body; on an error, stop with what the hub said."""
    if response.is_success:
        return response.json()
    try:
        body = response.json()
    except ValueError:
        body = {"detail": response.text or response.reason_phrase}
    detail = body.get("detail") if isinstance(body, dict) else body
    if isinstance(detail, list):  # a 422: one entry per bad field or broken rule
        detail = "; ".join(_field_error(item) for item in detail)
    request = response.request
    raise SystemExit(
        f"error: {request.method} {request.url.path} answered {response.status_code}: {detail}"
    )


def _field_error(item: Any) -> str:
    if isinstance(item, dict) and "msg" in item:
        where = ".".join(str(part) for part in item.get("loc", []))
        return f"{where}: {item['msg']}"
    return str(item)


def token() -> str:
    """GCS_TOKEN, or a fresh access token for GCS_USERNAME and GCS_PASSWORD."""
    if given := os.environ.get("GCS_TOKEN"):
        return given
    username = os.environ.get("GCS_USERNAME")
    password = os.environ.get("GCS_PASSWORD")
    if not username or not password:
        raise SystemExit("error: set GCS_TOKEN, or GCS_USERNAME and GCS_PASSWORD, to log in")
    answer = httpx.post(
        f"{hub_address()}/api/v1/auth/token",
        data={"username": username, "password": password},  # a form, not JSON
        timeout=30,
    )
    access_token: str = check(answer)["access_token"]
    return access_token


def connect(timeout_s: float = 60) -> httpx.Client:
    """A client for the hub's REST API that sends the token with every request."""
    return httpx.Client(
        base_url=hub_address(),
        headers={"Authorization": f"Bearer {token()}"},
        timeout=timeout_s,
    )


def accepted(answer: dict[str, Any], what: str) -> None:
    """A command's outcome: stop unless the flight controller accepted it."""
    outcome = answer["outcome"]
    if outcome["status"] != "accepted":
        raise SystemExit(f"error: {what}: {outcome['status']}: {outcome['message']}")


class LiveFeed:
    """The hub's live feed (WebSocket /api/v1/ws), kept as the latest state of each
    vehicle: ``vehicles[id]`` is the newest summary the hub sent for it."""

    def __init__(self, api: httpx.Client) -> None:
        # The feed takes the same bearer token as the REST API, in the same header.
        self.socket = websockets.sync.client.connect(
            feed_address(), additional_headers={"Authorization": api.headers["Authorization"]}
        )
        self.vehicles: dict[str, dict[str, Any]] = {}
        self._snapshot = False
        self.wait_until(lambda: self._snapshot, "the fleet", 30)

    def state(self, vehicle_id: str) -> dict[str, Any]:
        """The vehicle's latest state ({} before its first telemetry)."""
        return (self.vehicles.get(vehicle_id) or {}).get("state") or {}

    def __enter__(self) -> LiveFeed:
        return self

    def __exit__(self, *exc: object) -> None:
        self.socket.close()

    def wait_until(self, done: Callable[[], object], what: str, timeout_s: float = 120) -> None:
        """Follow the feed until ``done()`` holds; stop the example if it never does."""
        deadline = time.monotonic() + timeout_s
        while not done():
            remaining = deadline - time.monotonic()
            if remaining <= 0:
                raise SystemExit(f"error: gave up after {timeout_s:.0f} s waiting for {what}")
            try:
                message = json.loads(self.socket.recv(timeout=remaining))
            except TimeoutError:
                continue
            except websockets.exceptions.ConnectionClosed as closed:
                reason = closed_reason(closed)
                raise SystemExit(f"error: the hub closed the live feed: {reason}") from None
            if message["type"] == "fleet":  # the first message: every known vehicle
                self.vehicles = {vehicle["id"]: vehicle for vehicle in message["vehicles"]}
                self._snapshot = True
            elif message["type"] == "vehicles":  # then the vehicles that changed, batched
                # An update leaves out what it sent before (modes, ...): keep it.
                for vehicle in message["vehicles"]:
                    known = self.vehicles.get(vehicle["id"], {})
                    self.vehicles[vehicle["id"]] = {**known, **vehicle}
            elif message["type"] == "error":
                raise SystemExit(f"error: the hub said {message['code']}: {message['message']}")


def closed_reason(closed: websockets.exceptions.ConnectionClosed) -> str:
    """The close code and the hub's reason (4401: no valid token; see docs/websockets.md)."""
    if closed.rcvd is None:
        return "the connection was lost"
    return f"{closed.rcvd.code} {closed.rcvd.reason}"
