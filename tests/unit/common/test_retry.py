"""The one retry policy: full jitter under a doubling cap, so a fleet does not knock in step."""

from __future__ import annotations

import asyncio
import random
import statistics
from collections import Counter
from collections.abc import Callable, Coroutine, Iterator
from typing import Any

import pytest

from common.retry import Backoff, Retries, stop_retrying_when

AGENTS = 1000
ROUNDS = 6


@pytest.fixture(autouse=True)
def seeded() -> Iterator[None]:
    # tenacity draws from the module-level generator: seeded for a repeatable run, and
    # given back as it was.
    state = random.getstate()
    random.seed(14_8)
    yield
    random.setstate(state)


def test_the_cap_doubles_from_initial_to_max() -> None:
    backoff = Backoff(initial_s=0.5, max_s=10.0)
    assert [backoff.cap(n) for n in range(1, 8)] == [0.5, 1, 2, 4, 8, 10, 10]


@pytest.mark.parametrize("failures", [1, 3, 9])
def test_waits_are_uniform_between_zero_and_the_cap(failures: int) -> None:
    backoff = Backoff(initial_s=0.5, max_s=10.0)
    cap = backoff.cap(failures)
    waits = [backoff.delay(failures) for _ in range(4000)]
    assert all(0 <= wait <= cap for wait in waits)
    # Full jitter, not "equal jitter" (which never waits less than half the cap) and not
    # a fixed step: the whole of [0, cap] is used, evenly.
    assert min(waits) < 0.01 * cap
    assert max(waits) > 0.99 * cap
    assert statistics.mean(waits) == pytest.approx(cap / 2, rel=0.05)
    tenths = Counter(min(int(wait / cap * 10), 9) for wait in waits)
    assert all(300 <= tenths[tenth] <= 500 for tenth in range(10)), tenths


def test_a_success_starts_the_waits_over() -> None:
    retries = Retries(Backoff(initial_s=1.0, max_s=100.0))
    for _ in range(5):
        retries.next_delay()
    assert retries.backoff.cap(retries.failures) == 16
    retries.reset()
    assert retries.next_delay() <= 1.0


def test_a_fleet_that_lost_its_hub_does_not_knock_again_in_step() -> None:
    """A thousand agents lose the hub at the same instant and keep failing: in every
    round, their attempts spread over the round's window instead of landing together."""
    attempts: list[list[float]] = [[] for _ in range(ROUNDS)]

    async def agent() -> None:
        clock = 0.0

        async def sleep(delay: float) -> None:  # virtual time: the test takes no real time
            nonlocal clock
            clock += delay

        retries = Retries(Backoff(initial_s=0.5, max_s=10.0), sleep)
        for round_ in range(ROUNDS):
            await retries.wait()
            attempts[round_].append(clock)

    async def fleet() -> None:
        async with asyncio.TaskGroup() as tasks:
            for _ in range(AGENTS):
                tasks.create_task(agent())

    asyncio.run(fleet())
    for round_, instants in enumerate(attempts, start=1):
        # Lock-step would put all 1,000 in one 10 ms slot; the first round's window is
        # 0.5 s wide (50 slots, 20 agents each on average), later ones wider still.
        busiest = Counter(int(at / 0.01) for at in instants).most_common(1)[0][1]
        assert busiest <= AGENTS * 0.05, (round_, busiest)


def test_a_policy_must_grow_from_a_positive_start() -> None:
    with pytest.raises(ValueError, match="initial_s"):
        Backoff(initial_s=0.0, max_s=1.0)
    with pytest.raises(ValueError, match="initial_s"):
        Backoff(initial_s=2.0, max_s=1.0)


def test_a_loop_stopped_as_its_link_fails_ends_instead_of_retrying() -> None:
    asyncio.run(_stop_a_loop_as_its_link_fails())


def test_a_link_that_fails_without_a_stop_is_retried() -> None:
    """3.11's TaskGroup leaves a cancellation request of its own counted after a child
    fails: a loop that took that for a stop would never reconnect a lost link."""
    asyncio.run(_fail_a_link_three_times())


def _keep_link_up(
    reader: Callable[[], Coroutine[Any, Any, None]], attempts: list[int]
) -> Coroutine[Any, Any, None]:
    async def loop() -> None:
        retries = Retries(Backoff(initial_s=0.001, max_s=0.001))
        for _ in range(50):  # bounded, so the test ends even when the bug is back
            attempts.append(1)
            try:
                async with asyncio.TaskGroup() as tasks:
                    tasks.create_task(reader())
                return  # the link ended cleanly
            except* OSError:
                pass
            await retries.wait()

    return loop()


async def _stop_a_loop_as_its_link_fails() -> None:
    """SIGTERM cancels the agent at the moment the flight controller closes its socket:
    the link's TaskGroup raises only the reader's OSError (Python 3.11 drops the
    cancellation then), the loop catches it, and its next wait must still end the loop."""
    reader_started = asyncio.Event()
    stopping = asyncio.Event()
    attempts: list[int] = []

    async def reader() -> None:
        if attempts != [1]:
            raise OSError("connection refused")  # the flight controller is gone
        reader_started.set()
        try:
            await asyncio.Event().wait()
        except asyncio.CancelledError:
            raise OSError("flight controller closed the connection") from None

    stop_retrying_when(stopping)
    link = asyncio.create_task(_keep_link_up(reader, attempts))
    await reader_started.wait()
    stopping.set()
    link.cancel()
    await asyncio.wait({link}, timeout=5)
    assert link.cancelled(), f"the loop retried {len(attempts)} times after its stop"
    assert len(attempts) == 1


async def _fail_a_link_three_times() -> None:
    attempts: list[int] = []

    async def reader() -> None:
        if len(attempts) <= 3:
            await asyncio.sleep(0)
            raise OSError("no heartbeat for 3 s")

    stop_retrying_when(asyncio.Event())
    link = asyncio.create_task(_keep_link_up(reader, attempts))
    await asyncio.wait({link}, timeout=5)
    assert link.done()
    assert not link.cancelled(), "a lost link was taken for a stop"
    assert len(attempts) == 4
