"""Password hashing on its own small thread pool, with a bound on the work in flight.

argon2 costs about 64 MB and 120 ms per hash by design. Run in the default thread pool,
a flood of failed logins from many addresses (each under its rate limit) queued ahead of
the token lookups, audit writes and storage that the live service runs there, and held
one 64 MB buffer per concurrent attempt. Here it runs on ``threads`` workers of its own,
and once ``max_pending`` hashes are running or waiting, the next is refused at once (429)
instead of queueing: memory and CPU spent on passwords stay bounded, whatever comes in.

The workers also run at a lower CPU priority (nice +10; Linux gives each thread its own):
on a small machine (2 cores) two hashes at once had the event loop wait for a core, and
`/health` went over 100 ms for most of a login flood. Hashing yields to the live service
instead; a login then takes a little longer under load, which is the right way round.
"""

from __future__ import annotations

import asyncio
import functools
import logging
import os
import threading
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from typing import ParamSpec, TypeVar

from backend.errors import RateLimited

P = ParamSpec("P")
T = TypeVar("T")

THREAD_NAME_PREFIX = "password-hash"
BUSY_RETRY_AFTER_S = 1.0
HASH_THREAD_NICENESS = 10
log = logging.getLogger(__name__)


def _lower_priority() -> None:
    """Runs on each password thread as it starts: nice it below the event loop."""
    try:
        thread = threading.get_native_id()
        os.setpriority(
            os.PRIO_PROCESS, thread, os.getpriority(os.PRIO_PROCESS, thread) + HASH_THREAD_NICENESS
        )
    except (OSError, AttributeError) as error:  # not Linux, or not allowed: hash as is
        log.info("password threads keep their priority: %s", error)


class PasswordWork:
    def __init__(self, threads: int, max_pending: int) -> None:
        self.threads = threads
        self.max_pending = max_pending
        self._executor = ThreadPoolExecutor(
            threads, thread_name_prefix=THREAD_NAME_PREFIX, initializer=_lower_priority
        )
        # Only touched from the event loop: a plain semaphore, tested without waiting.
        self._slots = asyncio.Semaphore(max_pending)

    def check_room(self) -> None:
        """RateLimited if ``max_pending`` password checks are already running or waiting:
        also asked from a login's headers, before its body is read (early_refusal.py)."""
        if self._slots.locked():
            raise RateLimited(
                f"too many password checks in progress, the most ({self.max_pending}, "
                "password_hash_max_pending); try again in 1 s",
                BUSY_RETRY_AFTER_S,
            )

    async def run(self, work: Callable[P, T], *args: P.args, **kwargs: P.kwargs) -> T:
        """``work`` (which hashes or verifies a password) on the password threads;
        RateLimited at once if ``max_pending`` are already running or waiting."""
        self.check_room()
        async with self._slots:
            loop = asyncio.get_running_loop()
            # A cancelled request also cancels its job if no thread has taken it yet.
            return await loop.run_in_executor(
                self._executor, functools.partial(work, *args, **kwargs)
            )

    def close(self) -> None:
        self._executor.shutdown(wait=False, cancel_futures=True)
