"""The hub app served by uvicorn in a thread of the test process."""

from __future__ import annotations

import asyncio
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

import uvicorn

from backend.app import create_app
from backend.settings import HubSettings


class _NotifyingServer(uvicorn.Server):
    """A uvicorn server that signals once it is listening, so tests wait on an event."""

    def __init__(self, config: uvicorn.Config) -> None:
        super().__init__(config)
        self.listening = threading.Event()

    async def startup(self, sockets: Any = None) -> None:
        await super().startup(sockets)
        self.listening.set()


@contextmanager
def running_hub(settings: HubSettings, app: Any = None) -> Iterator[str]:
    """The hub app (``app``, else one made from ``settings``) served by uvicorn in a
    thread; yields its http:// base URL."""
    config = uvicorn.Config(
        app if app is not None else create_app(settings),
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
