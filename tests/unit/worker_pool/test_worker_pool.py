"""The hub's worker processes (backend/worker_pool.py), as real processes: a job past its
time limit, whose client went away or whose call was cancelled has its worker killed; the
pool refuses past its pending bound; a job's own error leaves its worker; the workers run
below the event loop's priority and end with the process that started them, even one
killed outright."""

from __future__ import annotations

import asyncio
import os
import signal
import subprocess
import sys
import textwrap
import time
from collections.abc import Awaitable, Callable
from pathlib import Path
from typing import TypeVar

import pytest

from backend.errors import RateLimited
from backend.worker_pool import WORKER_NICENESS, JobStopped, WorkerPool
from tests.support.waiting import poll_until

T = TypeVar("T")
FOREVER_S = 60.0  # a job that would outlast every test


def _alive(pid: int) -> bool:
    """Whether `pid` runs (a zombie, dead but not yet reaped by its new parent, does not)."""
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except (FileNotFoundError, ProcessLookupError):
        return False
    return state != "Z"


def _pool(**changes: int) -> WorkerPool:
    settings = {"workers": 1, "max_pending": 4, **changes}
    return WorkerPool(what="test jobs", setting="test_max_pending", **settings)


def _in_loop(pool: WorkerPool, test: Callable[[], Awaitable[T]]) -> T:
    """`test()` run in an event loop, the pool closed in it at the end, as the hub does."""

    async def run() -> T:
        try:
            return await test()
        finally:
            pool.close()

    return asyncio.run(run())


def test_a_job_past_its_time_limit_has_its_worker_killed() -> None:
    pool = _pool()

    async def run() -> tuple[int, float, int]:
        pid = await pool.run(FOREVER_S, os.getpid)  # the worker the next job goes to
        started = time.monotonic()
        with pytest.raises(JobStopped, match=r"longer than 0.3 s") as stopped:
            await pool.run(0.3, time.sleep, FOREVER_S)
        assert stopped.value.reason == "timeout"
        took = time.monotonic() - started
        return pid, took, await pool.run(FOREVER_S, os.getpid)

    killed, took, next_worker = _in_loop(pool, run)
    assert took < 5.0
    assert not _alive(killed)
    assert next_worker != killed  # a fresh worker took the next job


def test_a_job_whose_client_went_away_or_whose_call_was_cancelled_is_killed() -> None:
    pool = _pool(workers=2)

    async def run() -> list[int]:
        first = await pool.run(FOREVER_S, os.getpid)
        with pytest.raises(JobStopped, match="the client went away"):
            await pool.run(FOREVER_S, time.sleep, FOREVER_S, gone=asyncio.sleep(0.2))
        call = asyncio.ensure_future(pool.run(FOREVER_S, time.sleep, FOREVER_S))
        await asyncio.sleep(0.2)
        [second] = pool.pids()  # the first worker was killed; this one is busy
        call.cancel()
        with pytest.raises(asyncio.CancelledError):
            await call
        return [first, second]

    pids = _in_loop(pool, run)
    assert pids[0] != pids[1]
    for pid in pids:
        poll_until(lambda pid=pid: not _alive(pid), 5, f"worker {pid} killed")


def test_past_its_pending_bound_the_pool_refuses_with_a_retry_after() -> None:
    pool = _pool(max_pending=2)

    async def run() -> None:
        jobs = [asyncio.ensure_future(pool.run(FOREVER_S, time.sleep, 0.5)) for _ in range(2)]
        await asyncio.sleep(0)  # both taken: one running, one waiting for the worker
        refusal = r"2 test jobs .* the most \(test_max_pending\)"
        with pytest.raises(RateLimited, match=refusal) as no:
            await pool.run(FOREVER_S, time.sleep, 0.5)
        assert no.value.retry_after_s >= 1
        with pytest.raises(RateLimited):
            pool.check_room()  # the same refusal, asked from a request's headers
        await asyncio.gather(*jobs)
        pool.check_room()  # room again

    _in_loop(pool, run)


def test_a_job_s_own_error_is_raised_and_its_worker_kept_at_a_lower_priority() -> None:
    pool = _pool()

    async def run() -> tuple[int, int, int]:
        before = await pool.run(FOREVER_S, os.getpid)
        with pytest.raises(ValueError, match="invalid literal"):
            await pool.run(FOREVER_S, int, "not a number")
        niceness = await pool.run(FOREVER_S, os.nice, 0)
        return before, await pool.run(FOREVER_S, os.getpid), niceness

    before, after, niceness = _in_loop(pool, run)
    assert before == after
    assert niceness == os.nice(0) + WORKER_NICENESS


STARTER = textwrap.dedent(
    """
    import asyncio
    from backend.worker_pool import WorkerPool

    async def main():
        pool = WorkerPool(workers=1, max_pending=1, what="jobs", setting="x")
        # The worker says its pid once it is busy with a job that would last a minute.
        await pool.run(60, exec, "import os, time; print(os.getpid(), flush=True); time.sleep(60)")

    asyncio.run(main())
    """
)


@pytest.mark.parametrize("how", [signal.SIGKILL, signal.SIGTERM])
def test_a_worker_ends_with_the_process_that_started_it(how: signal.Signals) -> None:
    """However the hub ends, its workers and their fork server go with it, even a worker
    busy with a job (it never reads the hub's socket closing)."""
    with subprocess.Popen(
        [sys.executable, "-c", STARTER],
        stdout=subprocess.PIPE,
        text=True,
        env={**os.environ, "PYTHONPATH": os.getcwd()},
    ) as starter:
        try:
            assert starter.stdout is not None
            worker = int(starter.stdout.readline())
            stat = Path(f"/proc/{worker}/stat").read_text().rsplit(")", 1)[1].split()
            fork_server = int(stat[1])  # the worker's parent
            assert _alive(worker)
            assert _alive(fork_server)
            starter.send_signal(how)
            starter.wait(10)
        finally:
            starter.kill()
    poll_until(lambda: not _alive(worker), 10, "the worker to end")
    poll_until(lambda: not _alive(fork_server), 10, "the fork server to end")
