"""The hub's per-stream bookkeeping: duplicates, gaps to ask for, and how far to ack."""

from __future__ import annotations

from backend.storage.sequences import SequenceLedger, SequenceTracker, StreamKey

KEY = StreamKey("v1", "run", "telemetry")


def test_in_order_numbers_advance_the_acknowledged_point() -> None:
    tracker = SequenceTracker(contiguous=-1)
    assert [tracker.add(seq) for seq in range(4)] == [None] * 4
    assert tracker.contiguous == 3
    assert tracker.holds(2)
    assert not tracker.holds(4)


def test_a_jump_opens_one_gap_and_filling_it_closes_it() -> None:
    tracker = SequenceTracker(contiguous=4)
    assert tracker.add(9) == (5, 8)
    assert tracker.add(10) is None  # the same gap is not reported twice
    assert tracker.contiguous == 4
    for seq in (5, 6, 7, 8):
        tracker.add(seq)
    assert tracker.contiguous == 10
    assert tracker.ahead == set()


def test_giving_up_on_lost_numbers_lets_the_ack_move_on() -> None:
    tracker = SequenceTracker(contiguous=4)
    tracker.add(9)
    tracker.give_up(5, 8)
    assert tracker.contiguous == 9
    # A loss report cannot move the ack past what was actually stored.
    tracker.give_up(10, 1_000_000)
    assert tracker.contiguous == 9


def test_ledger_loads_a_stream_from_the_store_once_and_judges_a_batch() -> None:
    loads: list[StreamKey] = []

    def load(key: StreamKey) -> int | None:
        loads.append(key)
        return 7

    ledger = SequenceLedger(load)
    assert ledger.fresh([(KEY, 6), (KEY, 8), (KEY, 8), (KEY, 9)]) == [False, True, False, True]
    assert ledger.contiguous(KEY) == 7  # judging changes nothing
    gaps = ledger.record([(KEY, 8), (KEY, 11)])
    assert [(gap.first_seq, gap.last_seq) for gap in gaps] == [(9, 10)]
    assert ledger.contiguous(KEY) == 8
    assert loads == [KEY]


def test_a_huge_loss_is_recorded_as_a_range_at_once() -> None:
    tracker = SequenceTracker(contiguous=-1)
    tracker.add(2**40)
    tracker.give_up(0, 2**40 - 1)
    assert tracker.contiguous == 2**40
    assert tracker.settled == []


def test_a_loss_beyond_another_gap_waits_for_that_gap() -> None:
    tracker = SequenceTracker(contiguous=0)
    tracker.add(5)
    tracker.add(20)
    tracker.give_up(6, 19)
    assert tracker.contiguous == 0
    assert tracker.first_gap() == (1, 4)
    assert tracker.holds(10)
    for seq in range(1, 5):
        tracker.add(seq)
    assert tracker.contiguous == 20
    assert tracker.first_gap() is None


def test_a_set_aside_record_releases_the_ack() -> None:
    ledger = SequenceLedger(lambda key: 3)
    ledger.set_aside(KEY, 4)
    assert ledger.contiguous(KEY) == 4
    assert ledger.open_gaps([KEY]) == []


def test_a_stream_restored_with_open_holes_waits_for_them_and_no_more() -> None:
    tracker = SequenceTracker.restored(20, [(3, 6), (10, 10)])
    assert tracker.holes() == [(3, 6), (10, 10)]
    assert tracker.first_gap() == (3, 6)
    assert tracker.contiguous == 2
    assert tracker.holds(8)
    assert tracker.holds(20)
    assert not tracker.holds(4)
    tracker.give_up(3, 6)
    assert tracker.holes() == [(10, 10)]
    tracker.add(10)
    assert (tracker.contiguous, tracker.holes()) == (20, [])
    assert SequenceTracker.restored(20, []).contiguous == 20
    assert SequenceTracker.restored(None, []).contiguous == -1


def test_a_preview_changes_nothing_until_committed_and_names_the_holes_to_store() -> None:
    ledger = SequenceLedger(lambda key: 2)
    change = ledger.preview([(KEY, 5), (KEY, 6)])
    assert [(gap.first_seq, gap.last_seq) for gap in change.opened] == [(3, 4)]
    assert change.holes == {KEY: [(3, 4)]}
    assert ledger.contiguous(KEY) == 2
    assert not ledger.tracker(KEY).holds(5)
    ledger.commit(change)
    assert ledger.tracker(KEY).holds(5)
    unchanged = ledger.preview([(KEY, 7)])  # the holes are the same: nothing to store
    assert unchanged.holes == {}
    closed = ledger.preview([], [(KEY, 3, 4)])
    assert closed.holes == {KEY: []}
