"""A hub played frame by frame over a real WebSocket, for the agent's side of the protocol."""

from __future__ import annotations

import contextlib
import json
import queue
import threading
from typing import Any

from websockets.exceptions import ConnectionClosed
from websockets.sync.server import Server, ServerConnection, serve

from protocol.messages import (
    AGENT_WS_PATH,
    Welcome,
    encode,
)

ANSWER_S = 15.0


class ScriptedHub:
    """The hub's end of the agent's WebSocket: welcomes the agent, then passes its
    command results to the test; telemetry and events are read past."""

    def __init__(self) -> None:
        self.results: queue.Queue[dict[str, Any]] = queue.Queue()
        self.connections: queue.Queue[ServerConnection] = queue.Queue()
        self._server: Server = serve(self._handle, "127.0.0.1", 0)
        self.url = f"ws://127.0.0.1:{self._server.socket.getsockname()[1]}"
        self._thread = threading.Thread(target=self._server.serve_forever, daemon=True)

    def __enter__(self) -> ScriptedHub:
        self._thread.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self._server.shutdown()
        self._thread.join(10)

    def _handle(self, connection: ServerConnection) -> None:
        assert connection.request is not None
        assert connection.request.path == AGENT_WS_PATH
        hello = json.loads(connection.recv(timeout=10))
        connection.send(encode(Welcome(vehicle_id=hello["vehicle_id"])))
        self.connections.put(connection)
        with contextlib.suppress(ConnectionClosed):
            for frame in connection:
                message = json.loads(frame)
                if message["type"] == "command_result":
                    self.results.put(message)

    def answer_to(self, connection: ServerConnection, frame: str) -> dict[str, Any]:
        connection.send(frame)
        request_id = json.loads(frame)["request_id"]
        while True:
            result = self.results.get(timeout=ANSWER_S)
            if result["request_id"] == request_id:
                outcome: dict[str, Any] = result["outcome"]
                return outcome


def _command(request_id: str, command: object, timeout_s: object = 5.0) -> str:
    # JSON as a peer could write it: json.dumps spells NaN and Infinity as JavaScript does
    frame = {"type": "command", "request_id": request_id, "command": command}
    return json.dumps({**frame, "timeout_s": timeout_s})
