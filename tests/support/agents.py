"""Playing an agent to a real hub: a WebSocket peer that speaks the agent protocol frame
by frame, and what a test then waits for."""

from __future__ import annotations

import contextlib
import json
import time
from collections.abc import Iterator
from contextlib import contextmanager

import httpx
import pytest
from websockets.exceptions import ConnectionClosed
from websockets.sync.client import ClientConnection, connect

from protocol.messages import AGENT_WS_PATH, Telemetry, VehicleState, encode
from tests.support.hellos import agent_hello
from tests.support.waiting import poll_until


def ws_url(base_url: str, path: str) -> str:
    return base_url.replace("http://", "ws://") + path


def telemetry_frame(seq: int, alt: float = 1.0) -> str:
    return encode(Telemetry(seq=seq, time=time.time(), state=VehicleState(alt_rel=alt)))


@contextmanager
def websocket(url: str, headers: dict[str, str] | None = None) -> Iterator[ClientConnection]:
    """A client connection whose closing handshake may legitimately carry an error code."""
    stack = contextlib.ExitStack()
    socket = stack.enter_context(connect(url, additional_headers=headers or {}, max_size=None))
    try:
        yield socket
    finally:
        with contextlib.suppress(ConnectionClosed):
            stack.close()


class ScriptedAgent:
    """The agent's end of a real WebSocket. Unless ``delivery`` is asked for, the hub's
    acks and resend requests are read past, so a test sees commands and errors only."""

    def __init__(self, socket: ClientConnection, delivery: bool) -> None:
        self.socket = socket
        self._delivery = delivery

    def send(self, frame: str) -> None:
        self.socket.send(frame)

    def recv(self, timeout: float | None = None) -> str | bytes:
        deadline = None if timeout is None else time.monotonic() + timeout
        while True:
            remaining = None if deadline is None else max(0.0, deadline - time.monotonic())
            frame = self.socket.recv(timeout=remaining)
            if self._delivery or json.loads(frame).get("type") not in ("ack", "resend"):
                return frame


@contextmanager
def scripted_agent(
    base_url: str, vehicle_id: str, token: str, *, delivery: bool = False
) -> Iterator[ScriptedAgent]:
    """A real WebSocket peer speaking the agent protocol, frame by frame."""
    headers = {"Authorization": f"Bearer {token}"}
    with websocket(ws_url(base_url, AGENT_WS_PATH), headers) as socket:
        socket.send(encode(agent_hello(vehicle_id, stream_id="s1")))
        assert json.loads(socket.recv(timeout=5))["type"] == "welcome"
        yield ScriptedAgent(socket, delivery)


def close_code(socket: ClientConnection) -> tuple[int | None, str]:
    """Reads until the peer closes; its close code and reason."""

    def read_until_closed() -> None:
        while True:
            socket.recv(timeout=5)

    with pytest.raises(ConnectionClosed) as closed:
        read_until_closed()
    received = closed.value.rcvd
    return (received.code, received.reason) if received else (None, "")


def stored_count(api: httpx.Client, vehicle_id: str) -> int:
    page = api.get(
        f"/api/v1/vehicles/{vehicle_id}/telemetry", params={"start": 0, "limit": 10000}
    ).json()
    return len(page["samples"])


def wait_stored(api: httpx.Client, vehicle_id: str, count: int) -> None:
    # the batching writer flushes every 0.25 s; poll the real store
    what = f"{count} samples of {vehicle_id} stored"
    poll_until(lambda: stored_count(api, vehicle_id) >= count, 10, what, every_s=0.05)
