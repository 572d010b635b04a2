"""A dashboard that stops reading costs the others nothing: their updates keep flowing,
the hub holds at most the newest state per vehicle for it, and closes it (4408) once it
has read nothing for GCS_SLOW_CLIENT_TIMEOUT_S."""

from __future__ import annotations

import base64
import json
import os
import socket
import threading
import time
from collections.abc import Iterator
from contextlib import ExitStack, contextmanager
from pathlib import Path

import httpx
from websockets.sync.client import ClientConnection, connect

from backend.app import create_app
from backend.observability import metrics
from backend.realtime.client_feed import ClientFeed
from protocol.messages import AGENT_WS_PATH, CLIENT_WS_PATH, LiveState, VehicleState, encode
from tests.conftest import ADMIN_PASSWORD, hub_settings
from tests.support.api import access_token
from tests.support.hellos import agent_hello
from tests.support.hub_server import running_hub
from tests.support.waiting import poll_until

VEHICLES = 8
SLOW_CLIENT_TIMEOUT_S = 2.0


def _stalled_feed(base_url: str, token: str) -> socket.socket:
    """A live-feed connection that completes its handshake and then never reads: a tiny
    receive buffer, so the hub's sends back up after a few frames."""
    host, port = base_url.removeprefix("http://").split(":")
    raw = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
    raw.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4096)
    raw.connect((host, int(port)))
    key = base64.b64encode(os.urandom(16)).decode()
    raw.sendall(
        (
            f"GET {CLIENT_WS_PATH} HTTP/1.1\r\nHost: {host}:{port}\r\nUpgrade: websocket\r\n"
            f"Connection: Upgrade\r\nSec-WebSocket-Key: {key}\r\n"
            f"Sec-WebSocket-Version: 13\r\nAuthorization: Bearer {token}\r\n\r\n"
        ).encode()
    )
    return raw


@contextmanager
def _flying_fleet(base_url: str, tokens: dict[str, str]) -> Iterator[dict[str, float]]:
    """Agents sending their live state as fast as they can (each frame ~1.5 KB, so the
    stalled feed's buffers fill in moments); yields the newest time each one sent."""
    stop = threading.Event()
    newest: dict[str, float] = {}
    with ExitStack() as stack:
        agents: dict[str, ClientConnection] = {}
        for vehicle_id, token in tokens.items():
            agent = stack.enter_context(
                connect(
                    base_url.replace("http://", "ws://") + AGENT_WS_PATH,
                    additional_headers={"Authorization": f"Bearer {token}"},
                )
            )
            agent.send(encode(agent_hello(vehicle_id, stream_id=f"run-{vehicle_id}")))
            assert json.loads(agent.recv(timeout=10))["type"] == "welcome"
            agents[vehicle_id] = agent

        def fly() -> None:
            reason = "x" * 500  # the longest field: a fat frame
            while not stop.is_set():
                for vehicle_id, agent in agents.items():
                    now = time.time()
                    state = VehicleState(not_ready_reason=reason, alt_rel=now % 100)
                    agent.send(encode(LiveState(time=now, state=state)))
                    newest[vehicle_id] = now
                time.sleep(0.005)  # yield the GIL to the hub's thread

        flyer = threading.Thread(target=fly, daemon=True)
        flyer.start()
        try:
            yield newest
        finally:
            stop.set()
            flyer.join(10)


def test_a_dashboard_that_stops_reading_slows_no_one_and_is_closed(tmp_path: Path) -> None:
    settings = hub_settings(
        tmp_path,
        viz_enabled=False,
        slow_client_timeout_s=SLOW_CLIENT_TIMEOUT_S,
        ui_vehicle_interval_s=0.005,
        ui_batch_interval_s=0.005,
    )
    app = create_app(settings)
    closed_before = metrics.DROPPED.labels(reason="slow_client")._value.get()
    with running_hub(settings, app) as base_url:
        admin = access_token(base_url, "admin", ADMIN_PASSWORD)
        with httpx.Client(base_url=base_url, headers={"Authorization": f"Bearer {admin}"}) as api:
            tokens = {
                f"v{i}": api.post(f"/api/v1/vehicles/v{i}/agent-tokens").json()["token"]
                for i in range(VEHICLES)
            }
        hub = app.state.hub
        stalled = _stalled_feed(base_url, admin)
        try:
            feeds = poll_until(
                lambda: [f for f in hub.client_feeds if isinstance(f, ClientFeed)],
                10,
                "the stalled feed to be served",
            )
            slow_feed = feeds[0]
            with (
                connect(
                    base_url.replace("http://", "ws://") + CLIENT_WS_PATH,
                    additional_headers={"Authorization": f"Bearer {admin}"},
                    max_queue=None,
                ) as reader,
                _flying_fleet(base_url, tokens) as newest,
            ):
                most_pending = 0
                seen: dict[str, float] = {}
                deadline = time.monotonic() + 30
                # Read until the hub has closed the stalled feed, checking all along that
                # this reader keeps up and the stalled feed's backlog stays bounded.
                while slow_feed in hub.client_feeds:
                    assert time.monotonic() < deadline, "the stalled feed was never closed"
                    most_pending = max(most_pending, slow_feed.pending)
                    message = json.loads(reader.recv(timeout=10))
                    if message["type"] == "vehicles":
                        for vehicle in message["vehicles"]:
                            seen[vehicle["id"]] = vehicle["last_seen"]
                # Held for the stalled feed: one state per vehicle at most, never a queue.
                assert 0 < most_pending <= VEHICLES
                # Meanwhile the reader was served: it has every vehicle, and then the
                # newest state each agent sends from now on.
                assert set(seen) == set(tokens)
                mark = dict(newest)
                caught_up: dict[str, float] = {}
                while any(caught_up.get(v, 0.0) < sent for v, sent in mark.items()):
                    message = json.loads(reader.recv(timeout=10))
                    if message["type"] == "vehicles":
                        for vehicle in message["vehicles"]:
                            caught_up[vehicle["id"]] = vehicle["last_seen"]
        finally:
            stalled.close()
    assert metrics.DROPPED.labels(reason="slow_client")._value.get() == closed_before + 1
