"""Telemetry and events on their way to the hub: kept until the hub says they are stored.

Every frame stays in the outbox until an ``ack`` from the hub covers it, so a frame lost
with a dropped connection (or with a hub that died before committing it) is sent again.
While the hub is reachable the frames live in memory; when the link goes down they are
spilled to a SQLite file (if the agent has a directory for it), so an outage of hours,
or an agent restart, loses nothing. An SD card is spared the writes while all is well.

Ordering invariant: every frame on disk is older than every frame in memory. Spilling
moves all memory frames to the end of the file, and the sender drains the file first.

The outbox is bounded: past ``limit`` frames the oldest are dropped and counted, because
the newest state matters most to an operator watching a vehicle come back in range. A
hub asking for dropped frames is told they are unavailable, so it records the loss.
"""

from __future__ import annotations

import asyncio
import contextlib
import json
import logging
import sqlite3
import time
from collections import deque
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

from protocol.messages import Ack, Resend, SequencedKind, Unavailable

log = logging.getLogger(__name__)

# While the hub is away, frames are written in batches: an outage costs one small
# transaction per second or so rather than one per frame.
SPILL_BATCH = 50
SPILL_MAX_AGE_S = 1.0
DISK_READ_BATCH = 200
# A connected hub that stops acknowledging (its database is away) must not grow the
# agent's memory without bound either: past this, memory frames go to the spill file.
MEMORY_FRAMES = 3000


@dataclass(slots=True)
class Frame:
    stream_id: str
    kind: SequencedKind
    seq: int
    body: str  # the encoded message, as the current stream sends it
    queued_at: float
    disk_id: int | None = None  # its row in the spill file, once written there


class SpillFile:
    """The on-disk part of the outbox: one SQLite table in insertion order."""

    def __init__(self, path: Path) -> None:
        path.parent.mkdir(parents=True, exist_ok=True)
        self._db = sqlite3.connect(path, isolation_level=None, check_same_thread=False)
        self._db.execute("PRAGMA journal_mode=WAL")
        # A power cut may lose the last second of an outage; a torn database is worse.
        self._db.execute("PRAGMA synchronous=NORMAL")
        self._db.execute(
            "CREATE TABLE IF NOT EXISTS frames ("
            " id INTEGER PRIMARY KEY AUTOINCREMENT, stream_id TEXT NOT NULL,"
            " kind TEXT NOT NULL, seq INTEGER NOT NULL, body TEXT NOT NULL)"
        )
        self._db.execute(
            "CREATE INDEX IF NOT EXISTS frames_by_sequence ON frames (stream_id, kind, seq)"
        )
        self._db.execute("CREATE TABLE IF NOT EXISTS counters (name TEXT PRIMARY KEY, value INT)")
        self._rows = int(self._db.execute("SELECT count(*) FROM frames").fetchone()[0])

    def close(self) -> None:
        self._db.close()

    def __len__(self) -> int:
        return self._rows

    def append(self, frames: list[Frame]) -> None:
        row_ids = []
        with self._transaction():
            for frame in frames:
                cursor = self._db.execute(
                    "INSERT INTO frames (stream_id, kind, seq, body) VALUES (?, ?, ?, ?)",
                    (frame.stream_id, frame.kind, frame.seq, frame.body),
                )
                row_ids.append(cursor.lastrowid)
        # Only once committed: a frame marked as on disk is no longer kept in memory.
        for frame, row_id in zip(frames, row_ids, strict=True):
            frame.disk_id = row_id
        self._rows += len(frames)

    def after(self, disk_id: int, limit: int) -> list[Frame]:
        rows = self._db.execute(
            "SELECT id, stream_id, kind, seq, body FROM frames WHERE id > ? ORDER BY id LIMIT ?",
            (disk_id, limit),
        ).fetchall()
        return [
            Frame(stream, kind, seq, body, 0.0, row_id) for row_id, stream, kind, seq, body in rows
        ]

    def forget(self, stream_id: str, kind: SequencedKind, up_to_seq: int) -> None:
        deleted = self._db.execute(
            "DELETE FROM frames WHERE stream_id = ? AND kind = ? AND seq <= ?",
            (stream_id, kind, up_to_seq),
        )
        self._rows -= max(deleted.rowcount, 0)

    def trim(self, keep: int) -> int:
        """Drop the oldest frames beyond ``keep``; how many went."""
        excess = len(self) - keep
        if excess <= 0:
            return 0
        self._db.execute(
            "DELETE FROM frames WHERE id IN (SELECT id FROM frames ORDER BY id LIMIT ?)",
            (excess,),
        )
        self._rows -= excess
        return excess

    def sequences(self, stream_id: str, kind: SequencedKind, first: int, last: int) -> set[int]:
        rows = self._db.execute(
            "SELECT seq FROM frames WHERE stream_id = ? AND kind = ? AND seq BETWEEN ? AND ?",
            (stream_id, kind, first, last),
        )
        return {seq for (seq,) in rows}

    def counter(self, name: str) -> int:
        row = self._db.execute("SELECT value FROM counters WHERE name = ?", (name,)).fetchone()
        return int(row[0]) if row else 0

    def set_counter(self, name: str, value: int) -> None:
        self._db.execute(
            "INSERT INTO counters (name, value) VALUES (?, ?)"
            " ON CONFLICT (name) DO UPDATE SET value = excluded.value",
            (name, value),
        )

    def _transaction(self) -> _Transaction:
        return _Transaction(self._db)


class _Transaction:
    def __init__(self, db: sqlite3.Connection) -> None:
        self._db = db

    def __enter__(self) -> None:
        self._db.execute("BEGIN")

    def __exit__(self, kind: object, *rest: object) -> None:
        if kind is None:
            self._db.execute("COMMIT")
        elif self._db.in_transaction:  # SQLite may have rolled back already (disk full)
            self._db.execute("ROLLBACK")


class Outbox:
    """Frames in order, each kept until the hub acknowledges it."""

    def __init__(self, stream_id: str, limit: int, spill: SpillFile | None = None) -> None:
        self.stream_id = stream_id
        self._limit = limit
        self._spill = spill
        self._unsent: deque[Frame] = deque()  # memory frames due on this connection
        self._in_flight: deque[Frame] = deque()  # sent on this connection, not yet acked
        self._disk_cursor = 0  # the last spilled frame handed to the sender
        self._disk_backlog: deque[Frame] = deque()  # read ahead from the spill file
        self._connected = False
        self._ready = asyncio.Event()
        self.dropped = spill.counter("dropped") if spill else 0
        if spill is not None and (left := len(spill)):
            log.info("outbox: %d frames from an earlier run wait for the hub", left)
            self._ready.set()

    @contextlib.contextmanager
    def _disk(self) -> Iterator[None]:
        """Around every use of the spill file: a disk that fails (full, worn out, gone
        read-only) costs the outbox its disk, never the agent its link to the vehicle."""
        try:
            yield
        except sqlite3.Error as error:
            self._abandon_spill(error)

    def _abandon_spill(self, error: sqlite3.Error) -> None:
        log.error("outbox file failed (%s); keeping the outbox in memory from now on", error)
        # What the file holds and this connection has not sent yet comes back into
        # memory, if it can still be read (a full disk reads fine). Left in the file, it
        # would be sent again by the next run, and the hub drops duplicates.
        stranded: list[Frame] = []
        if self._spill is not None:
            with contextlib.suppress(sqlite3.Error):
                stranded = self._spill.after(self._disk_cursor, self._limit)
            with contextlib.suppress(sqlite3.Error):
                self._spill.close()
        self._spill = None
        for frame in [*self._in_flight, *stranded]:
            frame.disk_id = None
        self._unsent.extendleft(reversed(stranded))
        self._disk_backlog.clear()

    def __len__(self) -> int:
        on_disk = len(self._spill) if self._spill else 0
        in_memory = sum(1 for frame in self._in_flight if frame.disk_id is None)
        return on_disk + in_memory + len(self._unsent)

    def backlog(self) -> int:
        """Frames waiting to be sent on this connection (not counting those in flight)."""
        return len(self) - len(self._in_flight)

    def put(self, kind: SequencedKind, seq: int, body: str) -> None:
        self._unsent.append(Frame(self.stream_id, kind, seq, body, time.monotonic()))
        if self._spill is not None and self._should_spill():
            with self._disk():
                self._spill_memory()
        with self._disk():
            self._enforce_limit()
        self._ready.set()

    async def next_frame(self) -> str:
        """The next frame to send on this connection, waiting for one; it counts as in
        flight from now on, so a connection that drops takes nothing with it."""
        while True:
            frame = self._take()
            if frame is not None:
                self._in_flight.append(frame)
                return self._wire_body(frame)
            self._ready.clear()
            await self._ready.wait()

    def link_up(self) -> None:
        """A new connection: everything not yet acknowledged is due again."""
        self._connected = True
        self._rewind()

    def link_down(self) -> None:
        self._connected = False
        self._rewind()
        if self._spill is not None:
            with self._disk():
                self._spill_memory()

    def acknowledge(self, ack: Ack) -> None:
        acked: list[tuple[SequencedKind, int | None]] = [
            ("telemetry", ack.telemetry_seq),
            ("event", ack.event_seq),
        ]
        for kind, seq in acked:
            if seq is not None:
                self._forget(ack.stream_id, kind, seq)

    def _forget(self, stream_id: str, kind: SequencedKind, up_to_seq: int) -> None:
        def kept(frame: Frame) -> bool:
            return not (
                frame.seq <= up_to_seq and frame.kind == kind and frame.stream_id == stream_id
            )

        self._in_flight = deque(filter(kept, self._in_flight))
        self._unsent = deque(filter(kept, self._unsent))
        self._disk_backlog = deque(filter(kept, self._disk_backlog))
        if self._spill is not None:
            with self._disk():
                self._spill.forget(stream_id, kind, up_to_seq)

    def resend(self, request: Resend) -> list[Unavailable]:
        """Send the asked-for frames again; name the ones this outbox no longer holds."""
        first, last = request.first_seq, request.last_seq
        held = {
            frame.seq
            for frame in self._memory_frames()
            if frame.stream_id == request.stream_id
            and frame.kind == request.kind
            and first <= frame.seq <= last
        }
        if self._spill is not None:
            with self._disk():
                held |= self._spill.sequences(request.stream_id, request.kind, first, last)
        if held:
            self._rewind()
        return [
            Unavailable(
                stream_id=request.stream_id,
                kind=request.kind,
                first_seq=start,
                last_seq=end,
                reason=f"dropped by the vehicle's full outbox ({self.dropped} dropped so far)",
            )
            for start, end in _holes(sorted(held), first, last)
        ]

    def _take(self) -> Frame | None:
        if not self._disk_backlog and self._spill is not None:
            with self._disk():
                self._disk_backlog.extend(self._spill.after(self._disk_cursor, DISK_READ_BATCH))
        if self._disk_backlog:
            frame = self._disk_backlog.popleft()
            assert frame.disk_id is not None
            self._disk_cursor = frame.disk_id
            return frame
        return self._unsent.popleft() if self._unsent else None

    def _rewind(self) -> None:
        # Frames from the spill file come again from the file; memory frames go back
        # to the head of the queue, in their order.
        self._unsent.extendleft(reversed([f for f in self._in_flight if f.disk_id is None]))
        self._in_flight.clear()
        self._disk_backlog.clear()
        self._disk_cursor = 0
        if len(self):
            self._ready.set()

    def _should_spill(self) -> bool:
        in_memory = len(self._unsent) + sum(1 for f in self._in_flight if f.disk_id is None)
        if in_memory > MEMORY_FRAMES:
            return True
        if self._connected or not self._unsent:
            return False
        age = time.monotonic() - self._unsent[0].queued_at
        return len(self._unsent) >= SPILL_BATCH or age >= SPILL_MAX_AGE_S

    def _spill_memory(self) -> None:
        assert self._spill is not None
        in_flight = [frame for frame in self._in_flight if frame.disk_id is None]
        unsent = list(self._unsent)
        if not in_flight and not unsent:
            return
        self._spill.append(in_flight + unsent)
        if in_flight:
            # Already handed out on this connection: the sender must not take them again.
            last = in_flight[-1].disk_id
            assert last is not None
            self._disk_cursor = last
        self._unsent.clear()

    def _enforce_limit(self) -> None:
        if self._spill is not None:
            dropped = self._spill.trim(self._limit)
            if dropped:
                self._disk_backlog.clear()  # may hold rows that are gone now
        else:
            dropped = 0
            while len(self._unsent) + len(self._in_flight) > self._limit:
                (self._in_flight or self._unsent).popleft()
                dropped += 1
        if dropped:
            self.dropped += dropped
            if self._spill is not None:
                self._spill.set_counter("dropped", self.dropped)
            log.warning("outbox full (%d frames): dropped %d so far", self._limit, self.dropped)

    def _memory_frames(self) -> Iterator[Frame]:
        yield from self._in_flight
        yield from self._unsent

    def _wire_body(self, frame: Frame) -> str:
        if frame.stream_id == self.stream_id:
            return frame.body
        # Left from an earlier agent run: the frame names its own stream.
        message = json.loads(frame.body)
        message["stream_id"] = frame.stream_id
        return json.dumps(message)


def _holes(held: list[int], first: int, last: int) -> list[tuple[int, int]]:
    """The runs of numbers from ``first`` to ``last`` missing from sorted ``held``; the
    work is in what is held, so a request for a huge range costs nothing extra."""
    holes = []
    expected = first
    for seq in held:
        if seq > expected:
            holes.append((expected, seq - 1))
        expected = seq + 1
    if expected <= last:
        holes.append((expected, last))
    return holes
