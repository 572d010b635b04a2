"""The processes the bench starts, and their CPU and memory from /proc."""

from __future__ import annotations

import contextlib
import json
import os
import shutil
import signal
import subprocess
import sys
import time
import urllib.error
import urllib.request
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from bench.agent_footprint.mavlink_source import UdpSink

CLOCK_TICKS = os.sysconf("SC_CLK_TCK")
PAGE_KB = os.sysconf("SC_PAGE_SIZE") // 1024


@dataclass
class Measured:
    name: str
    process: subprocess.Popen[bytes] | None
    log_path: Path | None = None
    sink: UdpSink | None = None
    problem: str | None = None
    rss_mb: list[float] = field(default_factory=list)
    cpu_pct: list[float] = field(default_factory=list)
    cpu_mean: float = 0.0  # over the whole measured time
    forwarded: int = 0

    @property
    def pid(self) -> int:
        assert self.process is not None
        return self.process.pid


def _descendants(pid: int) -> list[int]:
    parents: dict[int, int] = {}
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            with contextlib.suppress(OSError, IndexError, ValueError):
                stat = (entry / "stat").read_text()
                parents[int(entry.name)] = int(stat.rsplit(")", 1)[1].split()[1])
    found, frontier = [pid], [pid]
    while frontier:
        children = [child for child, parent in parents.items() if parent in frontier]
        found += children
        frontier = children
    return found


def cpu_and_rss(pid: int) -> tuple[float, float]:
    """CPU seconds (user + system) and RSS in MB of a process and its descendants."""
    cpu_ticks, rss_pages = 0, 0
    for each in _descendants(pid):
        with contextlib.suppress(OSError, IndexError):
            fields_ = (Path(f"/proc/{each}/stat").read_text().rsplit(")", 1)[1]).split()
            cpu_ticks += int(fields_[11]) + int(fields_[12])  # utime, stime
            rss_pages += int(Path(f"/proc/{each}/statm").read_text().split()[1])
    return cpu_ticks / CLOCK_TICKS, rss_pages * PAGE_KB / 1024


def spawn(
    args: list[str], log_path: Path, env: dict[str, str] | None = None
) -> subprocess.Popen[bytes]:
    with log_path.open("wb") as log_file:  # the child keeps its own descriptor
        return subprocess.Popen(
            args,
            stdin=subprocess.DEVNULL,
            stdout=log_file,
            stderr=subprocess.STDOUT,
            env={**os.environ, **(env or {})},
            cwd=log_path.parent,
            start_new_session=True,
        )


def stop(process: subprocess.Popen[bytes] | None) -> None:
    if process is None or process.poll() is not None:
        return
    process.send_signal(signal.SIGTERM)
    try:
        process.wait(10)
    except subprocess.TimeoutExpired:
        process.kill()
        process.wait()


def wait_for_hub(base_url: str, hub: subprocess.Popen[bytes], timeout_s: float = 30) -> None:
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        if hub.poll() is not None:
            raise RuntimeError(f"hub exited with code {hub.returncode}")
        with (
            contextlib.suppress(urllib.error.URLError, ConnectionError),
            urllib.request.urlopen(f"{base_url}/api/v1/health", timeout=2),
        ):
            return
        time.sleep(0.2)  # waiting for a port to open: nothing else to wait on
    raise TimeoutError("hub did not answer its health check")


def hub_vehicles(base_url: str, password: str) -> dict[str, dict[str, Any]]:
    form = f"username=admin&password={password}".encode()
    with urllib.request.urlopen(f"{base_url}/api/v1/auth/token", data=form, timeout=5) as answer:
        token = json.load(answer)["access_token"]
    request = urllib.request.Request(
        f"{base_url}/api/v1/vehicles", headers={"Authorization": f"Bearer {token}"}
    )
    with urllib.request.urlopen(request, timeout=5) as answer:
        listed = json.load(answer)
    return {vehicle["id"]: vehicle for vehicle in listed}


def find_mavproxy(given: str | None) -> tuple[str | None, str | None]:
    """The mavproxy.py to run, or why there is none."""
    if given:
        return (given, None) if Path(given).is_file() else (None, f"{given} does not exist")
    beside = Path(sys.executable).parent / "mavproxy.py"
    found = str(beside) if beside.is_file() else shutil.which("mavproxy.py")
    if found:
        return found, None
    return None, (
        "mavproxy.py not found next to this Python or on PATH; install the bench extra "
        "(pip install -e '.[bench]') or pass --mavproxy PATH"
    )


@contextlib.contextmanager
def running(processes: list[Measured], extra: list[subprocess.Popen[bytes]]) -> Iterator[None]:
    try:
        yield
    finally:
        for measured in processes:
            stop(measured.process)
        for process in extra:
            stop(process)


def sample(processes: list[Measured], seconds: float) -> float:
    """Sample RSS and CPU once a second for ``seconds``; returns the time measured."""
    for m in processes:
        if m.problem is None and m.process is not None and m.process.poll() is not None:
            tail = m.log_path.read_text(errors="replace")[-600:] if m.log_path else ""
            m.problem = f"exited with code {m.process.returncode}: {tail.strip()}"
    live = {m.name: m for m in processes if m.problem is None and m.process is not None}
    first = {name: (time.monotonic(), cpu_and_rss(m.pid)[0]) for name, m in live.items()}
    previous = dict(first)
    counted_before = {name: m.sink.frames for name, m in live.items() if m.sink is not None}
    started = time.monotonic()
    while time.monotonic() - started < seconds:
        time.sleep(1.0)  # the sampling period
        for name, m in live.items():
            if m.process is not None and m.process.poll() is not None:
                m.problem = f"exited with code {m.process.returncode} while measured"
                continue
            now = time.monotonic()
            cpu_s, rss = cpu_and_rss(m.pid)
            then, cpu_then = previous[name]
            m.cpu_pct.append(100 * (cpu_s - cpu_then) / (now - then))
            m.rss_mb.append(rss)
            previous[name] = (now, cpu_s)
    elapsed = time.monotonic() - started
    for name, m in live.items():
        (then, cpu_then), (now, cpu_now) = first[name], previous[name]
        m.cpu_mean = 100 * (cpu_now - cpu_then) / (now - then)
        if m.sink is not None:
            m.forwarded = m.sink.frames - counted_before[name]
    return elapsed
