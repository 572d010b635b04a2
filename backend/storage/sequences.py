"""Which sequence numbers of each agent stream are stored: duplicates, gaps and acks.

An agent numbers its telemetry and its events, each from 0, per run (its stream). The
writer keeps, per (vehicle, stream, kind), the highest number below which everything
is stored, plus the numbers stored above a gap. From that it knows what is a duplicate,
which gap to ask the agent to fill, and how far it may tell the agent to forget.

The gaps still open (asked for, not yet filled nor reported lost) are stored with each
batch, so that a hub restarted after a crash still waits for them instead of taking
the store's highest number as the end of an unbroken run: every loss is then recorded.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from dataclasses import dataclass, field, replace
from typing import NamedTuple

from protocol.messages import SequencedKind


class StreamKey(NamedTuple):
    # A tuple, not a dataclass: the writer hashes and compares these several times per
    # stored frame, and a tuple does both in C.
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
    # Ranges beyond a gap that need no more waiting, as (first, last): the agent said it
    # no longer has them, or the store held them when the hub restarted. Kept as ranges,
    # so a loss of a million frames costs what a loss of one does.
    settled: list[tuple[int, int]] = field(default_factory=list)
    highest: int = -1

    def __post_init__(self) -> None:
        self.highest = max(self.highest, self.contiguous, *self.ahead)

    @classmethod
    def restored(cls, highest: int | None, holes: list[tuple[int, int]]) -> SequenceTracker:
        """A stream as the store left it: everything up to ``highest`` is stored, except
        the ``holes`` that were still open (sorted, disjoint, all below ``highest``)."""
        if highest is None:
            return cls(contiguous=-1)
        holes = sorted((first, last) for first, last in holes if first <= last < highest)
        if not holes:
            return cls(contiguous=highest)
        settled = []
        for (_, last), (following, _) in zip(holes, [*holes[1:], (highest + 1, 0)], strict=True):
            if last + 1 <= following - 1:
                settled.append((last + 1, following - 1))
        return cls(contiguous=holes[0][0] - 1, settled=settled, highest=highest)

    def copy(self) -> SequenceTracker:
        return replace(self, ahead=set(self.ahead), settled=list(self.settled))

    def holes(self) -> list[tuple[int, int]]:
        """Every range still waited for, lowest first (empty when nothing is missing)."""
        if self.contiguous >= self.highest:
            return []
        covered = sorted([(seq, seq) for seq in self.ahead] + self.settled)
        holes = []
        start = self.contiguous + 1
        for first, last in covered:
            if first > start:
                holes.append((start, first - 1))
            start = max(start, last + 1)
        if start <= self.highest:  # only while the tracker is inconsistent; never stored
            holes.append((start, self.highest))
        return holes

    def holds(self, seq: int) -> bool:
        return (
            seq <= self.contiguous
            or seq in self.ahead
            or any(first <= seq <= last for first, last in self.settled)
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
            self.settled.append((first, last))
            self._absorb()

    def first_gap(self) -> tuple[int, int] | None:
        """The lowest range still waited for, if any."""
        if self.contiguous >= self.highest:
            return None
        start = self.contiguous + 1
        above = [seq for seq in self.ahead if seq > start]
        above += [first for first, _ in self.settled if first > start]
        return start, min(above, default=self.highest + 1) - 1

    def _absorb(self) -> None:
        while True:
            following = self.contiguous + 1
            if following in self.ahead:
                self.ahead.remove(following)
                self.contiguous = following
                continue
            reached = [last for first, last in self.settled if first <= following]
            if not reached:
                return
            self.contiguous = max(self.contiguous, *reached)
            self.settled = [(f, last) for f, last in self.settled if last > self.contiguous]
            self.ahead = {seq for seq in self.ahead if seq > self.contiguous}


Holes = list[tuple[int, int]]


@dataclass
class LedgerChange:
    """What one batch does to the ledger, worked out before its transaction commits:
    the trackers it leaves, the gaps it opens, and the streams whose open gaps to store."""

    trackers: dict[StreamKey, SequenceTracker]
    opened: list[Gap]
    holes: dict[StreamKey, Holes]


class SequenceLedger:
    """All streams' trackers; ``load`` finds a stream's past on first sight (after a hub
    restart, what the database holds): its highest stored number, and through
    ``load_holes`` the gaps that were still open."""

    def __init__(
        self,
        load: Callable[[StreamKey], int | None],
        load_holes: Callable[[StreamKey], Holes] = lambda key: [],
    ) -> None:
        self._load = load
        self._load_holes = load_holes
        self._trackers: dict[StreamKey, SequenceTracker] = {}
        self._stored_holes: dict[StreamKey, Holes] = {}  # as the store has them now

    def tracker(self, key: StreamKey) -> SequenceTracker:
        tracker = self._trackers.get(key)
        if tracker is None:
            holes = self._load_holes(key)
            tracker = SequenceTracker.restored(self._load(key), holes)
            self._stored_holes[key] = tracker.holes()
            self._trackers[key] = tracker
        return tracker

    def preview(
        self,
        stored: Iterable[tuple[StreamKey, int]],
        losses: Iterable[tuple[StreamKey, int, int]] = (),
    ) -> LedgerChange:
        """The ledger after ``stored`` numbers and ``losses`` (first, last), on copies:
        nothing changes until ``commit``, so a batch whose transaction fails leaves the
        ledger as it was."""
        trackers: dict[StreamKey, SequenceTracker] = {}

        def copy_of(key: StreamKey) -> SequenceTracker:
            if key not in trackers:
                trackers[key] = self.tracker(key).copy()
            return trackers[key]

        opened = []
        for key, seq in stored:
            if (gap := copy_of(key).add(seq)) is not None:
                opened.append(Gap(key, *gap))
        for key, first, last in losses:
            copy_of(key).give_up(first, last)
        holes = {}
        for key, tracker in trackers.items():
            now_open = tracker.holes()
            if now_open != self._stored_holes.get(key, []):
                holes[key] = now_open
        return LedgerChange(trackers, opened, holes)

    def commit(self, change: LedgerChange) -> None:
        """The batch is stored (with ``change.holes``): its trackers become the ledger's."""
        self._trackers.update(change.trackers)
        self._stored_holes.update(change.holes)

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
        """``preview`` and take its trackers at once, where no holes are stored with it."""
        change = self.preview(stored)
        self._trackers.update(change.trackers)
        return change.opened

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
