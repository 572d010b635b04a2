"""The simulator for tests: in this process on a thread of its own (`serving`), or as a
process (`simulator_process`), and a MAVLink client's view of it through pymavlink's
mavutil, as the agent sees it."""

from __future__ import annotations

import asyncio
import queue
import signal
import subprocess
import sys
import threading
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from pymavlink import mavutil

from gcs.launcher import free_port
from simulator import ListenAddress, SimulatorConfig, SimulatorServer
from simulator.clock import Clock

REPO_ROOT = Path(__file__).resolve().parents[2]
SYSID = 7
GCS = {"source_system": 255, "source_component": 190}


def wait_for(
    connection: Any,
    types: list[str],
    predicate: Callable[[Any], bool],
    timeout_s: float,
    what: str,
    *,
    system_id: int = SYSID,
) -> Any:
    """The first message of ``types`` from ``system_id`` (the simulator's, unless told)
    that satisfies ``predicate``: the one MAVLink wait of the tests."""
    deadline = time.monotonic() + timeout_s
    while (remaining := deadline - time.monotonic()) > 0:
        message = connection.recv_match(type=types, blocking=True, timeout=remaining)
        if message is not None and message.get_srcSystem() == system_id and predicate(message):
            return message
    raise AssertionError(f"timed out after {timeout_s} s waiting for {what}")


def command(connection: Any, cmd: int, *params: float, timeout_s: float = 5.0) -> int:
    padded = [float(p) for p in params] + [0.0] * (7 - len(params))
    connection.mav.command_long_send(SYSID, 1, cmd, 0, *padded)
    ack = wait_for(
        connection, ["COMMAND_ACK"], lambda m: m.command == cmd, timeout_s, f"ack of {cmd}"
    )
    return int(ack.result)


@contextmanager
def mavlink_client(url: str) -> Iterator[Any]:
    connection = mavutil.mavlink_connection(url, **GCS)
    try:
        yield connection
    finally:
        connection.close()


# -- the simulator as its own process, as the demo and the agent tests run it --------


@contextmanager
def simulator_process(*args: str) -> Iterator[tuple[int, queue.Queue[str]]]:
    """``python -m simulator`` on a free port; yields (port, log lines)."""
    port = free_port()
    process = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "simulator",
            "--listen",
            f"tcp:127.0.0.1:{port}",
            "--system-id",
            str(SYSID),
            *args,
        ],
        cwd=REPO_ROOT,
        stdin=subprocess.DEVNULL,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        text=True,
    )
    assert process.stderr is not None
    lines: queue.Queue[str] = queue.Queue()
    stderr = process.stderr

    def pump_lines() -> None:
        for line in stderr:
            lines.put(line)

    pump = threading.Thread(target=pump_lines)
    pump.start()
    try:
        deadline = time.monotonic() + 20.0
        while True:
            remaining = deadline - time.monotonic()
            if remaining <= 0:
                raise AssertionError("simulator did not report listening within 20 s")
            try:
                line = lines.get(timeout=remaining)
            except queue.Empty:
                continue
            if "listening on" in line:
                break
        yield port, lines
    finally:
        if process.poll() is None:
            process.send_signal(signal.SIGTERM)
        try:
            code = process.wait(10)
        except subprocess.TimeoutExpired:
            process.kill()
            process.wait()
            raise
        finally:
            pump.join(10)
            process.stderr.close()
        assert code == 0, f"simulator exited with {code}"


# -- the simulator in-process, for the transport's details -----------------------------


@contextmanager
def serving(
    config: SimulatorConfig,
    *,
    clock: Clock | None = None,
) -> Iterator[tuple[SimulatorServer, ListenAddress]]:
    """A SimulatorServer on its own event loop thread; yields it and its bound address.
    ``clock`` replaces its sim clock (which times its physics and its streams)."""
    server = SimulatorServer(config, clock=clock)
    loop = asyncio.new_event_loop()
    started: queue.Queue[ListenAddress | BaseException] = queue.Queue()

    def run() -> None:
        asyncio.set_event_loop(loop)
        try:
            started.put(loop.run_until_complete(server.start()))
        except BaseException as error:
            started.put(error)
            return
        loop.run_forever()
        loop.run_until_complete(server.stop())

    thread = threading.Thread(target=run)
    thread.start()
    try:
        result = started.get(timeout=10)
        if isinstance(result, BaseException):
            raise result
        yield server, result
    finally:
        loop.call_soon_threadsafe(loop.stop)
        thread.join(10)
        loop.close()
