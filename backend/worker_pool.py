"""Worker processes for the CPU work the event loop must never wait for: survey plans, area
files' parsing, password hashes.

Why processes: in a thread of the hub's process, Python work holds the GIL, and the event
loop waits for it at each turn. Planning a survey in two threads held `/health` at a p99
of 170 ms and parsing KML in one at 234 ms (docs/deployer.md "The hub under floods"). A worker
process has its own interpreter: the event loop only sends the job and reads the answer.

Why not `concurrent.futures.ProcessPoolExecutor`: a job there cannot be stopped. Killing
its worker breaks the whole pool (BrokenProcessPool) for every other job. Here each worker
is a process of its own, fed one job at a time over a socket pair; a job past its time
limit, whose client went away, or whose request was cancelled has its worker killed
(SIGKILL: a plan deep in GEOS or numpy does not look at flags), and the next job gets a
fresh worker. Jobs beyond `workers` wait; beyond `max_pending` running or waiting, the
next is refused at once (RateLimited: a 429 with Retry-After), so neither memory nor the
queue grows with a flood.

The workers are forked by multiprocessing's fork server, started once (from a thread: it
imports `preload` first, numpy and shapely, which takes a second), so a killed worker is
replaced in milliseconds. They die with the hub, however it ends: each asks the kernel
for SIGKILL when its parent (the fork server) ends (PR_SET_PDEATHSIG), and the fork server
ends when the hub's end of its pipe closes, which the kernel does when the hub ends, even
by SIGKILL. They run at a lower CPU priority (nice +10), so on a small machine the event
loop gets a core first.
"""

from __future__ import annotations

import asyncio
import contextlib
import ctypes
import logging
import multiprocessing
import os
import pickle
import signal
import socket
import struct
import sys
from collections.abc import Awaitable, Callable, Sequence
from multiprocessing import forkserver
from multiprocessing.process import BaseProcess
from typing import Any, TypeVar

from backend.errors import GcsError, RateLimited

log = logging.getLogger(__name__)

T = TypeVar("T")
PR_SET_PDEATHSIG = 1  # linux/prctl.h
_HEADER = struct.Struct("!Q")  # each message: its length, then the pickle
WORKER_NICENESS = 10
BUSY_RETRY_AFTER_S = 1.0


class JobStopped(GcsError):
    """A job whose worker was killed before it answered; `reason` says why: "timeout",
    "gone" (its client went away), "cancelled" (its request was) or "died" (the worker
    ended on its own: out of memory, a crash)."""

    def __init__(self, reason: str, message: str) -> None:
        super().__init__(message)
        self.reason = reason


def _die_with_parent(hub_pid: int) -> None:
    """In a worker: SIGKILL when its parent ends; if the hub is gone already, end now.

    The fork server hands each child the write end of the pipe by which the hub keeps it
    alive (so that the child could ask it for processes of its own): a busy worker then
    kept the fork server alive after the hub ended, and the fork server it. Closed here,
    the fork server's only keeper is the hub."""
    alive_fd = getattr(forkserver._forkserver, "_forkserver_alive_fd", None)
    if isinstance(alive_fd, int):
        with contextlib.suppress(OSError):
            os.close(alive_fd)
        setattr(forkserver._forkserver, "_forkserver_alive_fd", None)  # noqa: B010 (private)
    if sys.platform.startswith("linux"):
        ctypes.CDLL(None, use_errno=True).prctl(PR_SET_PDEATHSIG, signal.SIGKILL, 0, 0, 0)
    try:
        os.kill(hub_pid, 0)
    except ProcessLookupError:  # the hub ended before the line above took effect
        os._exit(1)


def _read_message(sock: socket.socket) -> bytes | None:
    """One message (blocking, in a worker), or None once the hub closed its end."""
    header = sock.recv(_HEADER.size, socket.MSG_WAITALL)
    if len(header) < _HEADER.size:
        return None
    (size,) = _HEADER.unpack(header)
    data = bytearray(size)
    view, got = memoryview(data), 0
    while got < size:
        count = sock.recv_into(view[got:])
        if count == 0:
            return None
        got += count
    return bytes(data)


def _serve(sock: socket.socket, hub_pid: int, niceness: int) -> None:
    """A worker's life: jobs in, answers out, one at a time, until the hub closes."""
    _die_with_parent(hub_pid)
    # A Ctrl-C reaches the whole process group; stopping the workers is the hub's call.
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    with contextlib.suppress(OSError):
        os.nice(niceness)
    with sock:
        while (message := _read_message(sock)) is not None:
            function, args = pickle.loads(message)
            try:
                answer: tuple[bool, Any] = (True, function(*args))
            except Exception as error:  # the hub raises it again as the job's outcome
                answer = (False, error)
            try:
                data = pickle.dumps(answer, pickle.HIGHEST_PROTOCOL)
            except Exception as error:  # an answer that cannot cross: say so, not hang
                data = pickle.dumps((False, RuntimeError(f"unpicklable answer: {error!r}")))
            sock.sendall(_HEADER.pack(len(data)) + data)


class _Worker:
    def __init__(
        self, process: BaseProcess, reader: asyncio.StreamReader, writer: asyncio.StreamWriter
    ) -> None:
        self.process = process
        self.reader = reader
        self.writer = writer

    async def call(self, function: Callable[..., Any], args: tuple[Any, ...]) -> Any:
        payload = pickle.dumps((function, args), pickle.HIGHEST_PROTOCOL)
        self.writer.writelines([_HEADER.pack(len(payload)), payload])
        await self.writer.drain()
        (size,) = _HEADER.unpack(await self.reader.readexactly(_HEADER.size))
        ok, value = pickle.loads(await self.reader.readexactly(size))
        if not ok:
            raise value
        return value

    async def kill(self) -> None:
        """Killed and reaped (the fork server reports its end on the process's sentinel)."""
        with contextlib.suppress(ProcessLookupError):
            self.process.kill()
        self.writer.close()
        await asyncio.to_thread(self.process.join, 5.0)
        with contextlib.suppress(ValueError):  # still running: left to the fork server
            self.process.close()


class WorkerPool:
    """`workers` processes; `max_pending` jobs running or waiting for one. `what` and
    `setting` name the jobs and the setting of `max_pending` in a refusal's words."""

    def __init__(
        self,
        *,
        workers: int,
        max_pending: int,
        what: str,
        setting: str,
        preload: Sequence[str] = (),
        niceness: int = WORKER_NICENESS,
    ) -> None:
        self.workers = workers
        self.max_pending = max_pending
        self._what = what
        self._setting = setting
        self._niceness = niceness
        self._context = multiprocessing.get_context("forkserver")
        if preload:  # only before the fork server first starts; later it is a no-op
            self._context.set_forkserver_preload(list(preload))
        self._slots = asyncio.Semaphore(workers)  # only touched from the event loop
        self._idle: list[_Worker] = []
        self._busy: set[_Worker] = set()
        self._killing: set[asyncio.Future[None]] = set()  # kills nobody waits for
        self.pending = 0  # jobs running or waiting for a worker
        self._closed = False

    def check_room(self) -> None:
        """RateLimited if a job now would be refused: the early refusal, made from a
        request's headers before its body is read (backend/api/early_refusal.py)."""
        if self.pending >= self.max_pending:
            raise RateLimited(
                f"{self.pending} {self._what} are running or waiting, the most "
                f"({self._setting}); try again in {BUSY_RETRY_AFTER_S:g} s",
                BUSY_RETRY_AFTER_S,
            )

    async def run(
        self,
        timeout_s: float,
        function: Callable[..., T],
        *args: Any,
        gone: Awaitable[object] | None = None,
    ) -> T:
        """`function(*args)` in a worker (both pickled by reference and value: a module's
        function, plain or picklable arguments). Its worker is killed, and JobStopped
        raised, once it has run `timeout_s`, or once `gone` finishes (the client went
        away); a cancelled call kills it too. Its own exceptions are raised here."""
        self.check_room()
        self.pending += 1
        watcher = None if gone is None else asyncio.ensure_future(gone)
        try:
            async with self._slots:
                if self._closed:
                    raise self._stopped("cancelled", timeout_s)
                if watcher is not None and watcher.done():  # gone while it waited its turn
                    raise self._stopped("gone", timeout_s)
                worker = self._idle.pop() if self._idle else await self._start()
                return await self._on(worker, function, args, watcher, timeout_s)
        finally:
            self.pending -= 1
            if watcher is not None:
                watcher.cancel()

    async def _on(
        self,
        worker: _Worker,
        function: Callable[..., T],
        args: tuple[Any, ...],
        watcher: asyncio.Future[Any] | None,
        timeout_s: float,
    ) -> T:
        self._busy.add(worker)
        job = asyncio.ensure_future(worker.call(function, args))
        waiting = {job} if watcher is None else {job, watcher}
        try:
            done, _ = await asyncio.wait(
                waiting, timeout=timeout_s, return_when=asyncio.FIRST_COMPLETED
            )
        except asyncio.CancelledError:  # the request's task: nobody waits for the answer
            job.cancel()
            self._busy.discard(worker)
            killing = asyncio.ensure_future(worker.kill())
            self._killing.add(killing)
            killing.add_done_callback(self._killing.discard)
            raise
        self._busy.discard(worker)
        if job not in done:
            job.cancel()
            await worker.kill()
            raise self._stopped("gone" if watcher in done else "timeout", timeout_s)
        try:
            value: T = job.result()
        except (asyncio.IncompleteReadError, ConnectionError):
            await worker.kill()
            raise self._stopped("cancelled" if self._closed else "died", timeout_s) from None
        except Exception:  # the function's own error: its worker goes on
            self._idle.append(worker)
            raise
        self._idle.append(worker)
        return value

    def _stopped(self, reason: str, timeout_s: float) -> JobStopped:
        if reason == "timeout":
            return JobStopped(reason, f"took longer than {timeout_s:g} s")
        if reason == "gone":
            return JobStopped(reason, "the client went away")
        if reason == "cancelled":
            return JobStopped(reason, f"the hub is stopping; no more {self._what}")
        return JobStopped(reason, f"its worker process ended before it answered ({reason})")

    async def _start(self) -> _Worker:
        parent, child = socket.socketpair()
        process = self._context.Process(
            target=_serve, args=(child, os.getpid(), self._niceness), daemon=True
        )
        try:
            # In a thread: the first start also starts the fork server, which imports
            # `preload` before it answers.
            await asyncio.to_thread(process.start)
        finally:
            child.close()
        reader, writer = await asyncio.open_unix_connection(sock=parent)
        return _Worker(process, reader, writer)

    def pids(self) -> list[int]:
        """The workers' process ids (tests look for them after the hub ends)."""
        return [w.process.pid for w in (*self._idle, *self._busy) if w.process.pid is not None]

    def close(self) -> None:
        """Kill every worker now (the hub is stopping): the jobs end as JobStopped."""
        self._closed = True
        for worker in (*self._idle, *self._busy):
            with contextlib.suppress(ProcessLookupError, ValueError):
                worker.process.kill()
            worker.writer.close()
        self._idle.clear()
