"""Password hashing runs on threads of its own, and refuses at once when it is full."""

from __future__ import annotations

import asyncio
import threading

import pytest

from backend.auth.password_work import THREAD_NAME_PREFIX, PasswordWork
from backend.errors import RateLimited


def test_work_beyond_the_bound_is_refused_at_once_and_runs_on_its_own_threads() -> None:
    release = threading.Event()
    started = threading.Semaphore(0)
    names: list[str] = []

    def hash_slowly() -> str:
        names.append(threading.current_thread().name)
        started.release()
        release.wait(10)
        return "hashed"

    async def scenario() -> None:
        work = PasswordWork(threads=1, max_pending=2)
        try:
            running = asyncio.ensure_future(work.run(hash_slowly))
            waiting = asyncio.ensure_future(work.run(hash_slowly))
            await asyncio.to_thread(started.acquire, True, 10)  # one runs, one waits
            with pytest.raises(RateLimited) as refused:
                await asyncio.wait_for(work.run(hash_slowly), 1)
            assert refused.value.retry_after_s >= 1
            release.set()
            assert await asyncio.gather(running, waiting) == ["hashed", "hashed"]
            assert await work.run(lambda: "free again") == "free again"
        finally:
            release.set()
            work.close()

    asyncio.run(scenario())
    assert names
    assert all(name.startswith(THREAD_NAME_PREFIX) for name in names)


def test_hashing_runs_below_the_event_loops_cpu_priority() -> None:
    """The password threads are niced below the thread that runs the event loop, so a
    login flood's hashes yield the cores to the live service (Linux: per-thread nice)."""
    import os

    def own_niceness() -> int:
        return os.getpriority(os.PRIO_PROCESS, threading.get_native_id())

    async def compare() -> tuple[int, int]:
        work = PasswordWork(threads=1, max_pending=2)
        try:
            return own_niceness(), await work.run(own_niceness)
        finally:
            work.close()

    loop_nice, hash_nice = asyncio.run(compare())
    assert hash_nice >= min(19, loop_nice + 10)
