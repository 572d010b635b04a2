"""What an agent is told of its numbered frames: what is stored (acks) and what to send again."""

from __future__ import annotations

import asyncio
import logging
from collections.abc import Awaitable, Callable

from backend.storage.sequences import Gap, StreamKey
from protocol.messages import (
    Ack,
    Message,
    Resend,
)

log = logging.getLogger(__name__)

ACK_INTERVAL_S = 0.5  # an agent is told what is stored at most this often


class SequenceNews:
    """Acks and resend requests for one agent, paced, sent from the session's own task."""

    def __init__(self) -> None:
        # Acks (the newest per stream wins) and resend requests from the storage writer,
        # sent by this session's own task so the writer never waits on a socket.
        self._acks: dict[str, dict[str, int]] = {}
        self._resends: list[Resend] = []
        self._news = asyncio.Event()

    def acknowledge(self, key: StreamKey, seq: int) -> None:
        if seq >= 0:
            self._acks.setdefault(key.stream_id, {})[key.kind] = seq
            self._news.set()

    def request_resend(self, gap: Gap) -> None:
        log.info(
            "asking %s for %s %d-%d of stream %s",
            gap.key.vehicle_id,
            gap.key.kind,
            gap.first_seq,
            gap.last_seq,
            gap.key.stream_id,
        )
        self._resends.append(
            Resend(
                stream_id=gap.key.stream_id,
                kind=gap.key.kind,
                first_seq=gap.first_seq,
                last_seq=gap.last_seq,
            )
        )
        self._news.set()

    async def run(self, send: Callable[[Message], Awaitable[None]]) -> None:
        """Sends what is new until cancelled."""
        while True:
            await self._news.wait()
            self._news.clear()
            acks, self._acks = self._acks, {}
            resends, self._resends = self._resends, []
            for stream_id, by_kind in acks.items():
                await send(
                    Ack(
                        stream_id=stream_id,
                        telemetry_seq=by_kind.get("telemetry"),
                        event_seq=by_kind.get("event"),
                    )
                )
            for resend in resends:
                await send(resend)
            # Pacing: acks arriving meanwhile fold into one per stream. Without it a fleet
            # larger than the writer's batch gets an ack for nearly every frame it sends,
            # as many frames out as in; the agent keeps its frames until acked either way.
            await asyncio.sleep(ACK_INTERVAL_S)
