"""Slow request bodies are cut off: a client must send its body at a minimum rate.

A client that trickles a body (a byte every few seconds) would otherwise hold a
connection, a task and a file descriptor for as long as it likes; a thousand of them
starve the hub. uvicorn bounds idle keep-alive connections and the number of requests
in progress, but has no body read timeout, so this middleware adds one. Slow headers
(before the app sees a request) are the proxy's job: see deploy/nginx.conf.
"""

from __future__ import annotations

import asyncio

from fastapi import HTTPException
from starlette.types import ASGIApp, Message, Receive, Scope, Send


class SlowBodyTimeout:
    """A request's body must arrive within ``grace_s`` plus one second per
    ``min_rate_bps`` bytes received: large uploads on slow links pass, a trickle ends
    with 408 and a closed connection."""

    def __init__(self, app: ASGIApp, grace_s: float, min_rate_bps: float) -> None:
        self.app = app
        self.grace_s = grace_s
        self.min_rate_bps = min_rate_bps

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return
        loop = asyncio.get_running_loop()
        started = loop.time()
        received = 0
        complete = False

        async def timed_receive() -> Message:
            nonlocal received, complete
            if complete:  # after the body: waiting for a disconnect is not reading slowly
                return await receive()
            deadline = started + self.grace_s + received / self.min_rate_bps
            try:
                async with asyncio.timeout_at(deadline):
                    message = await receive()
            except TimeoutError:
                raise HTTPException(
                    status_code=408,
                    detail=(
                        f"request body too slow: under {self.min_rate_bps:g} bytes/s "
                        f"after {self.grace_s:g} s"
                    ),
                    headers={"Connection": "close"},
                ) from None
            if message["type"] == "http.request":
                received += len(message.get("body", b""))
                complete = not message.get("more_body", False)
            else:
                complete = True
            return message

        await self.app(scope, timed_receive, send)
