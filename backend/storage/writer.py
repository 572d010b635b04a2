"""The one batching writer: telemetry from the bus to the database in batches."""

from __future__ import annotations

import asyncio
import logging
import time
from dataclasses import dataclass

from sqlalchemy.exc import OperationalError

from backend.realtime.bus import ReliableSubscription
from backend.storage.repository import Repository, TelemetryEnvelope

log = logging.getLogger(__name__)


@dataclass
class WriterStats:
    written: int = 0
    batches: int = 0
    retries: int = 0
    last_batch_s: float = 0.0


class TelemetryWriter:
    """Collects up to ``batch_size`` samples or waits ``flush_interval_s``, then writes.

    Writes are idempotent (the store skips a (vehicle, stream, seq) it has), so a
    batch interrupted by shutdown is simply written again from ``finally``.
    """

    def __init__(
        self,
        repository: Repository,
        source: ReliableSubscription,
        batch_size: int,
        flush_interval_s: float,
        retry_backoff_s: float = 0.5,
    ) -> None:
        self._repository = repository
        self._source = source
        self._batch_size = batch_size
        self._flush_interval_s = flush_interval_s
        self._retry_backoff_s = retry_backoff_s
        self._batch: list[TelemetryEnvelope] = []
        self.stats = WriterStats()

    @property
    def backlog(self) -> int:
        return self._source.qsize() + len(self._batch)

    async def run(self) -> None:
        try:
            while True:
                await self._collect()
                await self._write_batch()
        finally:
            self._flush_on_shutdown()

    async def _collect(self) -> None:
        self._batch.append(await self._source.get())
        deadline = time.monotonic() + self._flush_interval_s
        while len(self._batch) < self._batch_size:
            remaining = deadline - time.monotonic()
            if remaining <= 0:
                break
            try:
                self._batch.append(await asyncio.wait_for(self._source.get(), remaining))
            except TimeoutError:
                break

    async def _write_batch(self) -> None:
        backoff = self._retry_backoff_s
        while True:
            try:
                started = time.monotonic()
                written = await asyncio.to_thread(self._repository.insert_telemetry, self._batch)
            except OperationalError as error:
                # The database is unavailable: keep the batch, wait, try again.
                self.stats.retries += 1
                log.warning("telemetry write failed, retrying in %.1f s: %s", backoff, error)
                await asyncio.sleep(backoff)
                backoff = min(backoff * 2, 10.0)
                continue
            self.stats.last_batch_s = time.monotonic() - started
            self.stats.written += written
            self.stats.batches += 1
            self._batch = []
            return

    def _flush_on_shutdown(self) -> None:
        while True:
            try:
                self._batch.append(self._source.get_nowait())
            except asyncio.QueueEmpty:
                break
        if self._batch:
            written = self._repository.insert_telemetry(self._batch)
            self.stats.written += written
            log.info("flushed %d telemetry samples on shutdown", len(self._batch))
            self._batch = []
