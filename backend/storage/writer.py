"""The one batching writer: telemetry and events from the bus to the database.

It sees each vehicle's samples in order and exactly once, so it also finds flights
(arm → disarm) and state changes as it stores them. Each batch is one transaction, and
every statement in it is idempotent, so a batch that failed (database away) or was cut
short by shutdown is simply written again.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Protocol

from sqlalchemy.exc import OperationalError, SQLAlchemyError
from sqlalchemy.exc import TimeoutError as PoolTimeout

from backend.observability import metrics
from backend.storage.flights import FlightClosed, FlightOpened, FlightTracker
from backend.storage.logbook import Logbook
from backend.storage.records import LostFrames, StoredEvent, StoredRecord, TelemetryEnvelope
from backend.storage.repository import Repository
from backend.storage.sequences import Gap, SequenceLedger, StreamKey
from common.retry import Backoff, Retries

# Told, after each commit, how far each touched agent stream is stored without a hole
# (its ack) and which holes newly appeared (to ask the agent for).
GAP_REASK_S = 10.0  # how often a gap that is still open is asked for again
COLLECT_TICK_S = 0.01  # while a batch gathers, how often the writer looks for more

SequenceNews = Callable[[dict[StreamKey, int], list[Gap]], None]

log = logging.getLogger(__name__)


class Inbox(Protocol):
    """Where the writer's records wait: the bus's reliable subscription, whose bound is the
    backpressure (backend.realtime.bus). Declared here, as storage imports no layer above."""

    @property
    def maxsize(self) -> int: ...

    def qsize(self) -> int: ...

    async def get(self) -> StoredRecord: ...

    def get_nowait(self) -> StoredRecord: ...


@dataclass
class WriterStats:
    written: int = 0  # telemetry samples stored
    duplicates: int = 0  # frames received again (replays after a reconnect), not stored twice
    events_written: int = 0
    lost: int = 0  # frames agents reported dropped from their full outboxes
    batches: int = 0
    retries: int = 0  # batches that had to wait for the database
    rejected: int = 0  # records the database refused outright (logged, set aside)
    last_batch_s: float = 0.0
    database_available: bool = True


class StorageWriter:
    """Collects up to ``batch_size`` records or waits ``flush_interval_s``, then writes."""

    def __init__(
        self,
        repository: Repository,
        logbook: Logbook,
        source: Inbox,
        batch_size: int,
        flush_interval_s: float,
        retry: Backoff = Backoff(initial_s=0.5, max_s=10.0),
    ) -> None:
        self._repository = repository
        self._logbook = logbook
        self._source = source
        self._batch_size = batch_size
        self._flush_interval_s = flush_interval_s
        self._retry = retry
        self._batch: list[StoredRecord] = []
        self._writing: asyncio.Future[None] | None = None
        self.tracker = FlightTracker(open_flights=logbook.open_flights())
        self.sequences = SequenceLedger(
            lambda key: repository.highest_seq(key.vehicle_id, key.stream_id, key.kind),
            lambda key: repository.open_gaps(key.vehicle_id, key.stream_id, key.kind),
        )
        self.on_sequences: SequenceNews | None = None
        self._gap_asked_at: dict[StreamKey, float] = {}
        self._news: tuple[dict[StreamKey, int], list[Gap]] | None = None
        self.stats = WriterStats()
        # Per vehicle, how old its oldest sample in the last batch that held one was when
        # that batch committed (the per-vehicle gcs_storage_write_lag_seconds on /metrics).
        self.vehicle_lag_s: dict[str, float] = {}

    @property
    def backlog(self) -> int:
        return self._source.qsize() + len(self._batch)

    @property
    def capacity(self) -> int:
        return self._source.maxsize

    async def run(self) -> None:
        try:
            while True:
                await self._collect()
                await self._write_until_stored()
        finally:
            if self._writing is not None and not self._writing.done():
                with contextlib.suppress(Exception):
                    await self._writing
            self._flush_on_shutdown()

    async def _collect(self) -> None:
        self._batch.append(await self._source.get())
        deadline = time.monotonic() + self._flush_interval_s
        while len(self._batch) < self._batch_size:
            # What is queued already is taken at once; when nothing is, the batch gathers
            # for a tick at a time rather than waking (with a timer) for every record.
            try:
                self._batch.append(self._source.get_nowait())
                continue
            except asyncio.QueueEmpty:
                pass
            remaining = deadline - time.monotonic()
            if remaining <= 0:
                break
            await asyncio.sleep(min(remaining, COLLECT_TICK_S))  # pacing, see above

    async def _write_until_stored(self) -> None:
        retries = Retries(self._retry)
        while True:
            try:
                started = time.monotonic()
                # Shielded: a write under way finishes even if the hub is stopping, so the
                # shutdown flush never runs beside it.
                self._writing = asyncio.ensure_future(asyncio.to_thread(self._write))
                await asyncio.shield(self._writing)
            except (OperationalError, PoolTimeout) as error:
                # The database is unavailable: keep the batch, wait, try again.
                self.stats.retries += 1
                if self.stats.database_available:
                    log.warning(
                        "database unavailable, holding %d records: %s", len(self._batch), error
                    )
                self.stats.database_available = False
                await retries.wait()
                continue
            except SQLAlchemyError as error:
                # Not the database going away: something in this batch it will never take.
                # Write the records one by one and set aside only the ones it refuses.
                log.error(
                    "batch of %d refused (%s); writing it record by record", len(self._batch), error
                )
                await asyncio.to_thread(self._write_one_by_one)
            self._tell_sequence_news()
            if not self.stats.database_available:
                log.info("database available again after %d retries", self.stats.retries)
            self.stats.database_available = True
            self.stats.last_batch_s = time.monotonic() - started
            self.stats.batches += 1
            metrics.STORAGE_BATCH_SECONDS.observe(self.stats.last_batch_s)
            metrics.QUEUE_DEPTH.labels(queue="storage").set(self.backlog)
            return

    def _write(self) -> None:
        """One batch in one transaction; the in-memory trackers change only once it has
        committed. A frame stored before (a replay after a reconnect) is skipped; a
        flight is identified by its vehicle and start time."""
        telemetry = [r for r in self._batch if isinstance(r, TelemetryEnvelope)]
        events = [r for r in self._batch if isinstance(r, StoredEvent)]
        losses = [r for r in self._batch if isinstance(r, LostFrames)]
        sequenced = [(_key(e), e.telemetry.seq) for e in telemetry]
        sequenced += [(_key(e), e.seq) for e in events if e.seq is not None]
        fresh = iter(self.sequences.fresh(sequenced))
        new_telemetry = [e for e in telemetry if next(fresh)]
        new_events = [e for e in events if e.seq is None or next(fresh)]
        forward = self._moving_forward(new_telemetry)
        # Samples the hub refused are handled as far as acks and gaps go (never asked for
        # again), and said once: a replay of them is refused again, not recorded again.
        # Each number keeps its place in the batch, so that a refused run (sent just
        # before the good sample after it) does not look like a gap that sample opened.
        place = {id(record): index for index, record in enumerate(self._batch)}
        handled = [
            (place[id(loss)], loss, (_key(loss), seq))
            for loss in losses
            if loss.refused
            for seq in range(loss.first_seq, loss.last_seq + 1)
        ]
        fresh_handled = self.sequences.fresh([number for _, _, number in handled])
        new_handled = [h for h, new in zip(handled, fresh_handled, strict=True) if new]
        said = {id(loss) for _, loss, _ in new_handled}
        loss_events = [_loss_event(x) for x in losses if not x.refused or id(x) in said]
        in_order = [(index, number) for index, _, number in new_handled]
        in_order += [(place[id(e)], (_key(e), e.telemetry.seq)) for e in new_telemetry]
        in_order.sort(key=lambda placed: placed[0])
        stored = [number for _, number in in_order]
        stored += [(_key(e), e.seq) for e in new_events if e.seq is not None]
        change = self.sequences.preview(
            stored,
            [(_key(loss), loss.first_seq, loss.last_seq) for loss in losses if not loss.refused],
        )
        tracker = self.tracker.copy()
        with self._repository.engine.begin() as connection:
            self._repository.insert_telemetry(new_telemetry, connection)
            # The gaps still open go with the batch that opened or closed them, so a hub
            # that dies between two batches restarts knowing what it still waits for.
            self._repository.replace_open_gaps(
                {(k.vehicle_id, k.stream_id, k.kind): holes for k, holes in change.holes.items()},
                connection,
            )
            plan = tracker.plan(forward)
            events_written = self._repository.insert_events(
                new_events + plan.events + loss_events, connection
            )
            for transition in plan.transitions:
                match transition:
                    case FlightOpened(vehicle_id=vehicle, time=at):
                        tracker.open_flights[vehicle] = self._logbook.open_flight(
                            vehicle, at, connection
                        )
                    case FlightClosed(vehicle_id=vehicle, time=at) if (
                        vehicle in tracker.open_flights
                    ):
                        flight_id = tracker.open_flights.pop(vehicle)
                        self._logbook.close_flight(flight_id, at, connection)
        self.tracker = tracker
        self.sequences.commit(change)
        gaps = change.opened
        touched = {key for key, _ in sequenced} | {_key(loss) for loss in losses}
        gaps = self._gaps_to_ask(gaps, touched)
        acks = {key: self.sequences.contiguous(key) for key in touched}
        self._merge_news(acks, gaps)
        self.stats.written += len(new_telemetry)
        metrics.STORAGE_ROWS.inc(len(new_telemetry))
        if new_telemetry:
            now = time.time()
            oldest_by_vehicle: dict[str, float] = {}
            for envelope in new_telemetry:
                sampled = envelope.telemetry.time
                known = oldest_by_vehicle.get(envelope.vehicle_id, sampled)
                oldest_by_vehicle[envelope.vehicle_id] = min(known, sampled)
            for vehicle, oldest in oldest_by_vehicle.items():
                self.vehicle_lag_s[vehicle] = max(0.0, now - oldest)
            metrics.STORAGE_WRITE_LAG.set(max(0.0, now - min(oldest_by_vehicle.values())))
        self.stats.duplicates += len(sequenced) - (len(stored) - len(new_handled))
        self.stats.events_written += events_written
        self.stats.lost += sum(
            loss.last_seq - loss.first_seq + 1 for loss in losses if not loss.refused
        )
        self._batch = []

    def _gaps_to_ask(self, opened: list[Gap], touched: set[StreamKey]) -> list[Gap]:
        """New gaps, and gaps still open from before, asked again now and then: a request
        lost with a dropped connection must not hold a stream's acks back for good."""
        now = time.monotonic()
        for gap in opened:
            self._gap_asked_at[gap.key] = now
        asking = list(opened)
        for gap in self.sequences.open_gaps(touched):
            if now - self._gap_asked_at.get(gap.key, -GAP_REASK_S) >= GAP_REASK_S:
                self._gap_asked_at[gap.key] = now
                asking.append(gap)
        return asking

    def _moving_forward(self, telemetry: list[TelemetryEnvelope]) -> list[TelemetryEnvelope]:
        """The samples newer than anything stored of their stream, in order: the ones
        flight detection follows (a gap filled late must not re-open an old flight)."""
        newest: dict[StreamKey, int] = {}
        forward = []
        for envelope in telemetry:
            key, seq = _key(envelope), envelope.telemetry.seq
            if key not in newest:
                newest[key] = self.sequences.tracker(key).highest
            if seq > newest[key]:
                newest[key] = seq
                forward.append(envelope)
        return forward

    def _merge_news(self, acks: dict[StreamKey, int], gaps: list[Gap]) -> None:
        if self._news is None:
            self._news = ({}, [])
        self._news[0].update(acks)
        self._news[1].extend(gaps)

    def _tell_sequence_news(self) -> None:
        news, self._news = self._news, None
        if news is not None and self.on_sequences is not None and (news[0] or news[1]):
            self.on_sequences(*news)

    def _write_one_by_one(self) -> None:
        records, self._batch = self._batch, []
        for record in records:
            self._batch = [record]
            try:
                self._write()
            except OperationalError:
                raise
            except SQLAlchemyError as error:
                self.stats.rejected += 1
                log.error("record set aside, the database refuses it: %r (%s)", record, error)
                self._batch = []
                self._give_up_on(record)

    def _give_up_on(self, record: StoredRecord) -> None:
        """A record the database will never take must not hold its stream's acks back,
        or the agent would keep it, and send it again, forever."""
        match record:
            case TelemetryEnvelope(telemetry=telemetry):
                self.sequences.set_aside(_key(record), telemetry.seq)
            case StoredEvent(seq=seq) if seq is not None:
                self.sequences.set_aside(_key(record), seq)

    def _flush_on_shutdown(self) -> None:
        """Store what was accepted: the batch in hand and everything still queued."""
        while True:
            try:
                self._batch.append(self._source.get_nowait())
            except asyncio.QueueEmpty:
                break
        if not self._batch:
            return
        count = len(self._batch)
        self._write()
        log.info("flushed %d records on shutdown", count)


def _key(record: TelemetryEnvelope | StoredEvent | LostFrames) -> StreamKey:
    if isinstance(record, TelemetryEnvelope):  # most records: checked first
        return StreamKey(record.vehicle_id, record.stream_id, "telemetry")
    if isinstance(record, StoredEvent):
        return StreamKey(record.vehicle_id, record.stream_id, "event")
    return StreamKey(record.vehicle_id, record.stream_id, record.kind)


def _loss_event(loss: LostFrames) -> StoredEvent:
    what = "telemetry samples" if loss.kind == "telemetry" else "events"
    return StoredEvent(
        loss.vehicle_id,
        "hub",
        None,
        time.time(),
        "data_lost",
        4,  # MAV_SEVERITY_WARNING
        f"{what} {loss.first_seq}-{loss.last_seq} of stream {loss.stream_id} "
        f"{'were refused, not stored' if loss.refused else 'never arrived'}: {loss.reason}",
    )
