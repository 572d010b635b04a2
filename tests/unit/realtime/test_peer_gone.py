"""A push to a dashboard that has already gone ends its feed as a disconnect does, not
with a traceback: uvicorn answers a send after the close with a RuntimeError, which the
feed's ``except* WebSocketDisconnect`` let through (233 tracebacks from 200 dashboards
that stopped reading and went away)."""

from __future__ import annotations

import asyncio

import pytest
from starlette.types import Message
from starlette.websockets import WebSocket, WebSocketDisconnect

from backend.realtime.frames import PeerConnection


class Peer(PeerConnection):
    surface = "client_ws"


async def closed_by_the_server(message: Message) -> None:
    # What uvicorn's websockets_sansio_impl.send raises once the connection has closed.
    raise RuntimeError(
        f"Unexpected ASGI message '{message['type']}', after sending 'websocket.close'."
    )


async def never_receives() -> Message:
    await asyncio.Event().wait()
    raise AssertionError("unreachable")


def gone_peer() -> Peer:
    scope = {"type": "websocket", "path": "/api/v1/ws", "headers": [], "client": ("127.0.0.1", 1)}
    websocket = WebSocket(scope, never_receives, closed_by_the_server)
    websocket.application_state = websocket.client_state = type(websocket.client_state).CONNECTED
    return Peer(websocket, max_frame_bytes=1024, max_bad_frames=3)


@pytest.mark.parametrize("send", ["text", "bytes", "close"])
def test_a_send_after_the_close_is_a_disconnect(send: str) -> None:
    async def attempt() -> None:
        peer = gone_peer()
        if send == "text":
            await peer.send_text("{}")
        elif send == "bytes":
            await peer.send_bytes(b"\x00")
        else:
            await peer.close(1000, "bye")

    with pytest.raises(WebSocketDisconnect) as ended:
        asyncio.run(attempt())
    assert ended.value.code == 1006
