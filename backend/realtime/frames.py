"""A WebSocket peer (agent or client): size-limited frames, serialized sends, and the
rule for bad frames (answer each with an error; close after too many)."""

from __future__ import annotations

import asyncio
import contextlib
import logging
from collections.abc import AsyncIterator

from starlette.websockets import WebSocket, WebSocketDisconnect

from backend.observability import metrics
from backend.observability.metrics import Surface, count_rejected
from protocol.messages import CloseCode, ErrorReply, Message, encode

log = logging.getLogger(__name__)


class FrameTooLarge(Exception):
    def __init__(self, size: int, limit: int) -> None:
        super().__init__(f"frame of {size} bytes is over the {limit}-byte limit")


# A close frame's reason: 123 bytes of UTF-8 at most (RFC 6455 5.5: a control frame's
# payload is 125 bytes, 2 of them the code). A longer one breaks the connection instead.
MAX_CLOSE_REASON_BYTES = 123


def close_reason(reason: str) -> str:
    """``reason`` cut to fit a close frame, on a character boundary, marked with "…"."""
    if len(reason.encode()) <= MAX_CLOSE_REASON_BYTES:
        return reason
    room = MAX_CLOSE_REASON_BYTES - len("…".encode())
    return reason.encode()[:room].decode(errors="ignore") + "…"


# A connection that ended without a close frame (RFC 6455 7.1.5).
ABNORMAL_CLOSURE = 1006


@contextlib.asynccontextmanager
async def _peer_gone_is_a_disconnect() -> AsyncIterator[None]:
    """A send on a connection that has already closed ends the connection's tasks as a
    disconnect does. uvicorn answers it with a RuntimeError ("Unexpected ASGI message
    'websocket.send', after sending 'websocket.close'"): a dashboard that went away while
    a push was due, which the feed's ``except* WebSocketDisconnect`` did not catch, so
    every such client left a traceback in the log (233 from 200 non-reading dashboards)."""
    try:
        yield
    except RuntimeError as error:
        raise WebSocketDisconnect(ABNORMAL_CLOSURE, str(error)) from error


class PeerConnection:
    surface: Surface  # where its frames are counted (backend/observability/metrics.py)

    def __init__(self, websocket: WebSocket, max_frame_bytes: int, max_bad_frames: int) -> None:
        self.websocket = websocket
        self.peer = f"{websocket.client.host}:{websocket.client.port}" if websocket.client else "?"
        self._max_frame_bytes = max_frame_bytes
        self._max_bad_frames = max_bad_frames
        # Command requests, replies and pushes come from different tasks.
        self._send_lock = asyncio.Lock()
        self.bad_frames = 0
        self._sent = metrics.MESSAGES_OUT.labels(surface=self.surface)
        self._received = metrics.MESSAGES_IN.labels(surface=self.surface)

    async def send(self, message: Message) -> None:
        await self.send_text(encode(message))

    async def send_text(self, text: str) -> None:
        """A frame encoded already: an update encoded once goes to every feed as is."""
        async with self._send_lock, _peer_gone_is_a_disconnect():
            await self.websocket.send_text(text)
        self._sent.inc()

    async def send_bytes(self, data: bytes) -> None:
        async with self._send_lock, _peer_gone_is_a_disconnect():
            await self.websocket.send_bytes(data)
        self._sent.inc()

    async def close(self, code: int, reason: str) -> None:
        async with self._send_lock, _peer_gone_is_a_disconnect():
            await self.websocket.close(code, close_reason(reason))

    async def receive(self) -> str | bytes | None:
        """The next frame, or None once the peer has gone."""
        message = await self.websocket.receive()
        if message["type"] == "websocket.disconnect":
            return None
        # An empty text frame stays text (a bad JSON frame), not an empty binary one.
        text = message.get("text")
        data: str | bytes = text if text is not None else (message.get("bytes") or b"")
        self._received.inc()
        size = len(data)
        if isinstance(data, str) and size * 4 > self._max_frame_bytes:
            size = len(data.encode())  # only near the limit: UTF-8 is 4 bytes a character at most
        if size > self._max_frame_bytes:
            count_rejected(self.surface)
            raise FrameTooLarge(size, self._max_frame_bytes)
        return data

    async def reject(self, reply: ErrorReply) -> None:
        """Answer a bad frame; past the limit, close the connection (raises disconnect)."""
        self.bad_frames += 1
        count_rejected(self.surface)
        log.info("bad frame from %s: %s", self.peer, reply.message)
        await self.send(reply)
        if self.bad_frames >= self._max_bad_frames:
            await self.send(
                ErrorReply(code="too_many_errors", message="closing: too many bad frames")
            )
            await self.close(CloseCode.POLICY_VIOLATION, "too many bad frames")
            raise WebSocketDisconnect(CloseCode.POLICY_VIOLATION)
