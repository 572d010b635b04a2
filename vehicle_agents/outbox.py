"""Telemetry waiting to reach the hub: bounded, ordered, with a counted drop policy."""

from __future__ import annotations

import asyncio
import collections
import logging

log = logging.getLogger(__name__)


class Outbox:
    """Frames in order. When full, the oldest frame is dropped and counted, because the
    newest state matters most to an operator watching a vehicle come back in range."""

    def __init__(self, limit: int) -> None:
        self._frames: collections.deque[str] = collections.deque()
        self._limit = limit
        self._not_empty = asyncio.Event()
        self.dropped = 0

    def __len__(self) -> int:
        return len(self._frames)

    def put(self, frame: str) -> None:
        if len(self._frames) >= self._limit:
            self._frames.popleft()
            self.dropped += 1
            if self.dropped == 1 or self.dropped % 1000 == 0:
                log.warning("outbox full (%d frames): dropped %d so far", self._limit, self.dropped)
        self._frames.append(frame)
        self._not_empty.set()

    async def peek(self) -> str:
        """The oldest frame, waiting for one; it stays queued until ``pop`` confirms it."""
        while not self._frames:
            self._not_empty.clear()
            await self._not_empty.wait()
        return self._frames[0]

    def pop(self) -> None:
        self._frames.popleft()
