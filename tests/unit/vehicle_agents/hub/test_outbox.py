"""The agent's outbox: nothing is forgotten before the hub acknowledges it, frames keep
their order across memory and disk, and the drop policy is explicit."""

from __future__ import annotations

import asyncio
import json
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest

from protocol.messages import Ack, Resend
from vehicle_agents.hub.outbox import Outbox, SpillFile


def _put(outbox: Outbox, seqs: range, kind: str = "telemetry") -> None:
    for seq in seqs:
        outbox.put(kind, seq, json.dumps({"type": kind, "seq": seq}))  # type: ignore[arg-type]


Drain = Callable[[Outbox], list[int]]


@pytest.fixture
def loop() -> Iterator[asyncio.AbstractEventLoop]:
    """One loop for the whole test: the outbox's wake-up event belongs to one loop."""
    loop = asyncio.new_event_loop()
    yield loop
    loop.close()


@pytest.fixture
def drain(loop: asyncio.AbstractEventLoop) -> Drain:
    """Everything the sender would send now, as sequence numbers."""

    def drain_now(outbox: Outbox) -> list[int]:
        async def take_all() -> list[int]:
            sent = []
            while True:
                try:
                    async with asyncio.timeout(0.05):
                        frame = await outbox.next_frame()
                except TimeoutError:
                    return sent
                sent.append(json.loads(frame)["seq"])

        return loop.run_until_complete(take_all())

    return drain_now


def test_unacknowledged_frames_go_again_on_the_next_connection(drain: Drain) -> None:
    outbox = Outbox("run-a", limit=100)
    outbox.link_up()
    _put(outbox, range(5))
    assert drain(outbox) == [0, 1, 2, 3, 4]
    outbox.acknowledge(Ack(stream_id="run-a", telemetry_seq=2))
    outbox.link_down()
    outbox.link_up()
    assert drain(outbox) == [3, 4]
    assert len(outbox) == 2


def test_spilled_frames_survive_an_agent_restart_and_name_their_stream(
    tmp_path: Path, loop: asyncio.AbstractEventLoop
) -> None:
    path = tmp_path / "outbox.sqlite"
    first_run = Outbox("run-a", limit=1000, spill=SpillFile(path))
    _put(first_run, range(60))  # the hub is unreachable: these go to disk in batches
    first_run.link_down()
    assert len(first_run) == 60

    second_run = Outbox("run-b", limit=1000, spill=SpillFile(path))
    second_run.link_up()
    _put(second_run, range(3))

    async def frames() -> list[dict[str, object]]:
        return [json.loads(await second_run.next_frame()) for _ in range(63)]

    sent = loop.run_until_complete(frames())
    # The earlier run's frames come first, in order, each naming the earlier stream.
    assert [f["seq"] for f in sent[:60]] == list(range(60))
    assert {f.get("stream_id") for f in sent[:60]} == {"run-a"}
    assert [(f["seq"], f.get("stream_id")) for f in sent[60:]] == [(0, None), (1, None), (2, None)]
    second_run.acknowledge(Ack(stream_id="run-a", telemetry_seq=59))
    second_run.acknowledge(Ack(stream_id="run-b", telemetry_seq=2))
    assert len(second_run) == 0


def test_order_is_kept_across_memory_and_disk(tmp_path: Path, drain: Drain) -> None:
    outbox = Outbox("run", limit=1000, spill=SpillFile(tmp_path / "o.sqlite"))
    outbox.link_up()
    _put(outbox, range(10))
    assert drain(outbox) == list(range(10))
    outbox.link_down()  # 0-9 were in flight: all of them go to disk, in order
    _put(outbox, range(10, 20))
    outbox.link_up()
    _put(outbox, range(20, 25))
    assert drain(outbox) == list(range(25))


def test_full_outbox_drops_the_oldest_and_counts_them(tmp_path: Path, drain: Drain) -> None:
    spill = SpillFile(tmp_path / "o.sqlite")
    outbox = Outbox("run", limit=100, spill=spill)
    _put(outbox, range(250))
    outbox.link_down()
    assert len(outbox) == 100
    assert outbox.dropped == 150
    outbox.link_up()
    assert drain(outbox) == list(range(150, 250))
    # The count survives a restart, so the drop stays visible.
    assert Outbox("run2", limit=100, spill=SpillFile(tmp_path / "o.sqlite")).dropped == 150


def test_memory_only_outbox_is_bounded_too(drain: Drain) -> None:
    outbox = Outbox("run", limit=10)
    _put(outbox, range(25))
    assert outbox.dropped == 15
    outbox.link_up()
    assert drain(outbox) == list(range(15, 25))


def test_resend_replays_what_is_held_and_names_what_was_dropped(
    tmp_path: Path, drain: Drain
) -> None:
    outbox = Outbox("run", limit=100, spill=SpillFile(tmp_path / "o.sqlite"))
    _put(outbox, range(150))
    outbox.link_down()
    outbox.link_up()
    assert drain(outbox) == list(range(50, 150))
    unavailable = outbox.resend(
        Resend(stream_id="run", kind="telemetry", first_seq=40, last_seq=60)
    )
    assert [(u.first_seq, u.last_seq) for u in unavailable] == [(40, 49)]
    assert "full outbox" in unavailable[0].reason
    assert drain(outbox)[:11] == list(range(50, 61))  # sent again from the start


def test_events_and_telemetry_are_acknowledged_separately(drain: Drain) -> None:
    outbox = Outbox("run", limit=100)
    outbox.link_up()
    _put(outbox, range(3), kind="telemetry")
    _put(outbox, range(3), kind="event")
    drain(outbox)
    outbox.acknowledge(Ack(stream_id="run", telemetry_seq=2))
    assert len(outbox) == 3
    outbox.acknowledge(Ack(stream_id="run", event_seq=1))
    outbox.link_down()
    outbox.link_up()
    assert drain(outbox) == [2]


def test_a_resend_of_a_huge_range_is_answered_at_once(drain: Drain) -> None:
    outbox = Outbox("run", limit=100)
    _put(outbox, range(10, 13))
    request = Resend(stream_id="run", kind="telemetry", first_seq=0, last_seq=2**62)
    unavailable = outbox.resend(request)
    assert [(u.first_seq, u.last_seq) for u in unavailable] == [(0, 9), (13, 2**62)]


def test_a_full_disk_costs_the_outbox_its_file_not_the_agent(tmp_path: Path, drain: Drain) -> None:
    spill = SpillFile(tmp_path / "o.sqlite")
    spill._db.execute("PRAGMA max_page_count = 8")  # a card with almost no room left
    outbox = Outbox("run", limit=10_000, spill=spill)
    _put(outbox, range(2000))  # the hub is away: spilling fails part way, nothing raises
    outbox.link_down()
    outbox.link_up()
    sent = drain(outbox)
    assert sorted(set(sent)) == list(range(2000)), "every frame is still sent"
    assert sent == sorted(sent)


def test_backlog_counts_what_waits_to_be_sent(tmp_path: Path, drain: Drain) -> None:
    outbox = Outbox("run", limit=1000, spill=SpillFile(tmp_path / "o.sqlite"))
    _put(outbox, range(120))  # the hub is away: most of it goes to disk
    assert outbox.backlog() == 120
    outbox.link_up()
    drain(outbox)
    assert outbox.backlog() == 0
    assert len(outbox) == 120  # sent, not yet acknowledged
