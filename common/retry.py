"""One retry policy for every reconnect: exponential backoff with full jitter.

The agent's links (hub, flight controller, .tlog uploads) and the hub's storage writer
all wait between failed attempts. With the same fixed delays everywhere, a thousand
agents that lost one hub would knock again at the same instants, every round. Full
jitter spreads them out: after the n-th failure in a row the wait is drawn uniformly
from ``[0, min(max_s, initial_s * 2**(n-1))]`` (tenacity's ``wait_random_exponential``,
the "Full Jitter" of the AWS architecture blog).

``Backoff`` is the policy, a named timeout object with defaults; ``Retries`` counts one
run of failures under it and waits, with the sleep injected so tests run fast. The
loops decide themselves what a failure and a success are (a hub session counts as a
success once it was welcomed, however it ends), so each keeps its own ``Retries``
rather than handing its body to a tenacity ``Retrying``.

Here, not in the agent, because the hub's writer uses it too; it imports nothing of ours.
"""

from __future__ import annotations

import asyncio
from collections.abc import Awaitable, Callable
from contextvars import ContextVar
from dataclasses import dataclass

from tenacity import RetryCallState, Retrying, wait_exponential, wait_random_exponential

Sleep = Callable[[float], Awaitable[None]]


@dataclass(frozen=True)
class Backoff:
    """Waits between failed attempts: full jitter under a cap that doubles from
    ``initial_s`` after each failure in a row, up to ``max_s``."""

    initial_s: float = 0.5
    max_s: float = 10.0

    def __post_init__(self) -> None:
        if not 0 < self.initial_s <= self.max_s:
            raise ValueError(f"backoff needs 0 < initial_s <= max_s, got {self}")

    def cap(self, failures: int) -> float:
        """The longest wait after ``failures`` failures in a row."""
        return float(wait_exponential(multiplier=self.initial_s, max=self.max_s)(_after(failures)))

    def delay(self, failures: int) -> float:
        """One wait after ``failures`` failures in a row, drawn from ``[0, cap(failures)]``."""
        wait = wait_random_exponential(multiplier=self.initial_s, max=self.max_s)
        return float(wait(_after(failures)))


class Retries:
    """One run of failures under a ``Backoff``: each failure waits longer (on average),
    a success starts over."""

    def __init__(self, backoff: Backoff, sleep: Sleep = asyncio.sleep) -> None:
        self.backoff = backoff
        self._sleep = sleep
        self.failures = 0

    def next_delay(self) -> float:
        """Count one more failure; the wait before the next attempt."""
        self.failures += 1
        return self.backoff.delay(self.failures)

    async def sleep(self, delay: float) -> None:
        _raise_if_stopping()
        await self._sleep(delay)

    async def wait(self) -> float:
        """Count one more failure and wait before the next attempt; the wait it took."""
        delay = self.next_delay()
        await self.sleep(delay)
        return delay

    def reset(self) -> None:
        """The attempt succeeded: the next failure waits as little as the first."""
        self.failures = 0


def stop_retrying_when(stopping: asyncio.Event) -> None:
    """From now on, every retry loop in this task, and in the tasks it starts, ends (with
    ``CancelledError``) instead of waiting for another attempt once ``stopping`` is set.

    The process's stop signal sets it as well as cancelling the main task, because the
    cancellation alone can be lost: on Python 3.11 a ``TaskGroup`` whose child fails while
    the task around it is being cancelled raises only the child's error. The link's reader
    reports the closed socket at the moment SIGTERM arrives, the loop's ``except*`` takes
    the error, and the loop would retry for ever, deaf to every further SIGTERM.
    (``Task.cancelling()`` cannot tell: 3.11's ``TaskGroup`` leaves a request of its own
    uncounted-back after any child fails, stop or no stop.)
    """
    _stopping.set(stopping)


_stopping: ContextVar[asyncio.Event | None] = ContextVar("retry_stopping", default=None)


def _raise_if_stopping() -> None:
    stopping = _stopping.get()
    if stopping is not None and stopping.is_set():
        raise asyncio.CancelledError


def _after(failures: int) -> RetryCallState:
    # tenacity's wait strategies read only the attempt number from the call state; the
    # first retry follows attempt 1, so n failures in a row are attempt n.
    state = RetryCallState(retry_object=_NO_RETRYING, fn=None, args=(), kwargs={})
    state.attempt_number = max(failures, 1)
    return state


_NO_RETRYING = Retrying()
