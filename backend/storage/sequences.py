"""Which sequence numbers of each agent stream are stored: duplicates, gaps and acks.

An agent numbers its telemetry and its events, each from 0, per run (its stream). The
writer keeps, per (vehicle, stream, kind), the highest number below which everything
is stored, plus the numbers stored above a gap. From that it knows what is a duplicate,
which gap to ask the agent to fill, and how far it may tell the agent to forget.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from dataclasses import dataclass, field

from gcs.protocol import SequencedKind


@dataclass(frozen=True)
class StreamKey:
    vehicle_id: str
    stream_id: str
    kind: SequencedKind


@dataclass(frozen=True)
class Gap:
    key: StreamKey
    first_seq: int
    last_seq: int


@dataclass
class SequenceTracker:
    contiguous: int  # every number up to this one is stored (or known lost)
    ahead: set[int] = field(default_factory=set)  # stored beyond a gap, waiting for it
    # Ranges beyond a gap that the agent said it no longer has, as (first, last): kept as
    # ranges, so a loss of a million frames costs what a loss of one does.
    lost: list[tuple[int, int]] = field(default_factory=list)
    highest: int = -1

    def __post_init__(self) -> None:
        self.highest = max(self.highest, self.contiguous, *self.ahead)

    def holds(self, seq: int) -> bool:
        return (
            seq <= self.contiguous
            or seq in self.ahead
            or any(first <= seq <= last for first, last in self.lost)
        )

    def add(self, seq: int) -> tuple[int, int] | None:
        """Record a stored number; the gap it opens below itself, if it opens one."""
        if self.holds(seq):
            return None
        highest = self.highest
        gap = (highest + 1, seq - 1) if seq > highest + 1 else None
        self.ahead.add(seq)
        self.highest = max(highest, seq)
        self._absorb()
        return gap

    def give_up(self, first: int, last: int) -> None:
        """Numbers the agent no longer has: stop waiting for them. Only what lies in a
        gap counts; a loss report cannot move the ack past what was actually stored."""
        first = max(first, self.contiguous + 1)
        last = min(last, self.highest)
        if first <= last:
            self.lost.append((first, last))
            self._absorb()

    def first_gap(self) -> tuple[int, int] | None:
        """The lowest range still waited for, if any."""
        if self.contiguous >= self.highest:
            return None
        start = self.contiguous + 1
        above = [seq for seq in self.ahead if seq > start]
        above += [first for first, _ in self.lost if first > start]
        return start, min(above, default=self.highest + 1) - 1

    def _absorb(self) -> None:
        while True:
            following = self.contiguous + 1
            if following in self.ahead:
                self.ahead.remove(following)
                self.contiguous = following
                continue
            reached = [last for first, last in self.lost if first <= following]
            if not reached:
                return
            self.contiguous = max(self.contiguous, *reached)
            self.lost = [(f, last) for f, last in self.lost if last > self.contiguous]
            self.ahead = {seq for seq in self.ahead if seq > self.contiguous}


class SequenceLedger:
    """All streams' trackers; ``load`` finds a stream's past on first sight (after a hub
    restart, what the database holds)."""

    def __init__(self, load: Callable[[StreamKey], int | None]) -> None:
        self._load = load
        self._trackers: dict[StreamKey, SequenceTracker] = {}

    def tracker(self, key: StreamKey) -> SequenceTracker:
        tracker = self._trackers.get(key)
        if tracker is None:
            stored = self._load(key)
            tracker = SequenceTracker(contiguous=-1 if stored is None else stored)
            self._trackers[key] = tracker
        return tracker

    def fresh(self, keys: Iterable[tuple[StreamKey, int]]) -> list[bool]:
        """For each (stream, number), whether it is new: not stored, and not earlier in
        the same batch. Changes nothing; ``record`` does, once the batch is committed."""
        seen_in_batch: set[tuple[StreamKey, int]] = set()
        verdicts = []
        for key, seq in keys:
            new = not self.tracker(key).holds(seq) and (key, seq) not in seen_in_batch
            seen_in_batch.add((key, seq))
            verdicts.append(new)
        return verdicts

    def in_order(self, key: StreamKey, seq: int) -> bool:
        """Newer than anything stored: a sample that moves the stream forward (a gap
        filled late is stored, but does not replay history into live analysis)."""
        return seq > self.tracker(key).highest

    def record(self, stored: Iterable[tuple[StreamKey, int]]) -> list[Gap]:
        gaps = []
        for key, seq in stored:
            opened = self.tracker(key).add(seq)
            if opened is not None:
                gaps.append(Gap(key, *opened))
        return gaps

    def give_up(self, key: StreamKey, first: int, last: int) -> None:
        self.tracker(key).give_up(first, last)

    def set_aside(self, key: StreamKey, seq: int) -> None:
        """A frame the database refused: handled, as far as acks and gaps go."""
        self.tracker(key).add(seq)

    def open_gaps(self, keys: Iterable[StreamKey]) -> list[Gap]:
        """The lowest gap still waited for in each of these streams."""
        gaps = []
        for key in keys:
            if (gap := self.tracker(key).first_gap()) is not None:
                gaps.append(Gap(key, *gap))
        return gaps

    def contiguous(self, key: StreamKey) -> int:
        return self.tracker(key).contiguous
