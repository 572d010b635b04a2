"""Test helpers that talk to real servers over real sockets."""

from __future__ import annotations

import asyncio
import json
import threading
import time
from collections.abc import Callable, Iterator
from contextlib import ExitStack, contextmanager
from typing import Any

import httpx
import uvicorn
from websockets.sync.client import ClientConnection, connect

from backend.app import create_app
from backend.settings import HubSettings
from gcs.protocol import CLIENT_WS_PATH


class _NotifyingServer(uvicorn.Server):
    """A uvicorn server that signals once it is listening, so tests wait on an event."""

    def __init__(self, config: uvicorn.Config) -> None:
        super().__init__(config)
        self.listening = threading.Event()

    async def startup(self, sockets: Any = None) -> None:
        await super().startup(sockets)
        self.listening.set()


@contextmanager
def running_hub(settings: HubSettings) -> Iterator[str]:
    """The hub app served by uvicorn in a thread; yields its http:// base URL."""
    config = uvicorn.Config(
        create_app(settings),
        host="127.0.0.1",
        port=settings.port,
        log_level="warning",
        ws_max_size=settings.max_frame_bytes,
        lifespan="on",
    )
    server = _NotifyingServer(config)
    thread = threading.Thread(target=lambda: asyncio.run(server.serve()), daemon=True)
    thread.start()
    if not server.listening.wait(20):
        raise RuntimeError("hub did not start listening within 20 s")
    try:
        yield f"http://127.0.0.1:{settings.port}"
    finally:
        server.should_exit = True
        thread.join(20)


class FleetWatcher:
    """Follows the hub's client WebSocket and waits for a state to appear."""

    def __init__(self, base_url: str, token: str) -> None:
        ws_url = base_url.replace("http://", "ws://") + CLIENT_WS_PATH
        self._stack = ExitStack()
        self._socket: ClientConnection = self._stack.enter_context(
            connect(ws_url, additional_headers={"Authorization": f"Bearer {token}"})
        )
        self.vehicles: dict[str, dict[str, Any]] = {}

    def close(self) -> None:
        self._stack.close()

    def __enter__(self) -> FleetWatcher:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def wait_until(
        self, predicate: Callable[[dict[str, dict[str, Any]]], bool], timeout_s: float, what: str
    ) -> dict[str, dict[str, Any]]:
        deadline = time.monotonic() + timeout_s
        while not predicate(self.vehicles):
            remaining = deadline - time.monotonic()
            if remaining <= 0:
                raise AssertionError(
                    f"timed out after {timeout_s} s waiting for {what}; "
                    f"last state: {json.dumps(self.vehicles)[:2000]}"
                )
            try:
                frame = self._socket.recv(timeout=remaining)
            except TimeoutError:
                continue
            message = json.loads(frame)
            if message["type"] == "fleet":
                self.vehicles = {vehicle["id"]: vehicle for vehicle in message["vehicles"]}
            elif message["type"] == "vehicle":
                self.vehicles[message["vehicle"]["id"]] = message["vehicle"]
        return self.vehicles

    def state(self, vehicle_id: str) -> dict[str, Any]:
        return self.vehicles.get(vehicle_id, {}).get("state") or {}


def access_token(base_url: str, username: str, password: str) -> str:
    """A bearer token through the OAuth2 password flow, as an integration gets one."""
    response = httpx.post(
        f"{base_url}/api/v1/auth/token", data={"username": username, "password": password}
    )
    response.raise_for_status()
    token: str = response.json()["access_token"]
    return token


def api_client(base_url: str, token: str, timeout_s: float = 30) -> httpx.Client:
    return httpx.Client(
        base_url=base_url, timeout=timeout_s, headers={"Authorization": f"Bearer {token}"}
    )
