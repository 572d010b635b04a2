"""`gcs demo` starts the whole fleet as processes and Ctrl-C stops every one of them."""

from __future__ import annotations

import json
import os
import re
import signal
import subprocess
import sys
from pathlib import Path

import httpx
import pytest
from pymavlink import mavutil

from gcs.launcher import free_port
from tests.support.api import access_token
from tests.support.waiting import poll_until
from tests.support.watcher import FleetWatcher

pytestmark = pytest.mark.integration


def _children(pid: int) -> set[int]:
    found: set[int] = set()
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                stat = (entry / "stat").read_text()
            except OSError:
                continue
            if int(stat.rsplit(")", 1)[1].split()[1]) == pid:
                found.add(int(entry.name))
    return found


def test_demo_runs_the_fleet_and_stops_cleanly_on_ctrl_c(tmp_path: Path) -> None:
    port = free_port()
    demo = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "gcs",
            "demo",
            "--vehicles",
            "2",
            "--port",
            str(port),
            "--data-dir",
            str(tmp_path),
            "--speedup",
            "2",
        ],
        stdout=subprocess.PIPE,
        text=True,
        env=os.environ.copy(),
    )
    try:
        assert demo.stdout is not None
        banner = ""
        for line in demo.stdout:  # ends when the demo prints its banner (or dies)
            banner += line
            if "Press Ctrl-C" in line:
                break
        assert f"http://127.0.0.1:{port}/" in banner
        children = _children(demo.pid)
        assert len(children) == 1 + 2 * 2  # hub, two simulators, two agents
        secrets = json.loads((tmp_path / "demo-secrets.json").read_text())
        assert f"admin / {secrets['admin_password']}" in banner
        token = access_token(f"http://127.0.0.1:{port}", "admin", secrets["admin_password"])
        with FleetWatcher(f"http://127.0.0.1:{port}", token) as watcher:
            watcher.wait_until(
                lambda v: sum(1 for x in v.values() if x["connected"] and x["state"]) == 2,
                30,
                "both demo vehicles online",
            )
        assert httpx.get(f"http://127.0.0.1:{port}/api/v1/health").json()["connected"] == 2
        # Each simulator's MAVLink port, where QGroundControl can attach beside the agent.
        for system_id, vehicle in ((1, "sim_1"), (2, "sim_2")):
            address = re.search(rf"^\s+{vehicle}\s+(tcp:127\.0\.0\.1:\d+)$", banner, re.M)
            assert address, f"no MAVLink port for {vehicle} in the banner:\n{banner}"
            assert _heartbeat_source(address.group(1)) == system_id

        demo.send_signal(signal.SIGINT)
        assert demo.wait(30) == 0
        still_running = {
            pid
            for pid in children
            if Path(f"/proc/{pid}").exists()
            and "Z" not in Path(f"/proc/{pid}/stat").read_text().split()[2]
        }
        assert still_running == set()
    finally:
        if demo.poll() is None:
            demo.kill()
            demo.wait()
        if demo.stdout is not None:
            demo.stdout.close()


def _heartbeat_source(address: str) -> int:
    """The system id of the first HEARTBEAT a ground station gets at ``address``."""
    qgc = mavutil.mavlink_connection(address, source_system=255, source_component=190)
    try:
        heartbeat = qgc.recv_match(type="HEARTBEAT", blocking=True, timeout=10)
        assert heartbeat is not None, f"no HEARTBEAT at {address}"
        return int(heartbeat.get_srcSystem())
    finally:
        qgc.close()


def _alive(pids: set[int]) -> set[int]:
    """Those of ``pids`` still running (a zombie has ended; only its entry is left)."""
    alive = set()
    for pid in pids:
        try:
            state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
        except OSError:
            continue
        if state != "Z":
            alive.add(pid)
    return alive


def _as_a_background_job() -> None:
    """What a non-interactive shell does to a job it starts with `&`: SIGINT ignored.
    SIGHUP at its default whatever the suite inherited: under `nohup make test` it is
    ignored, which the launcher honours on purpose, and the SIGHUP case would wait out
    its timeout (as it did once, 32 s, when the suite ran under nohup)."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGHUP, signal.SIG_DFL)


@pytest.mark.parametrize(
    "signum", [signal.SIGINT, signal.SIGTERM, signal.SIGHUP, signal.SIGKILL], ids=lambda s: s.name
)
def test_no_child_outlives_the_launcher_whatever_ends_it(
    tmp_path: Path, signum: signal.Signals
) -> None:
    demo = subprocess.Popen(
        [
            *(sys.executable, "-m", "gcs", "demo", "--vehicles", "1"),
            *("--port", str(free_port()), "--data-dir", str(tmp_path)),
        ],
        stdout=subprocess.PIPE,
        text=True,
        # Started as `gcs demo &` from a script is: SIGINT ignored from the start.
        preexec_fn=_as_a_background_job,
    )
    try:
        assert demo.stdout is not None
        for line in demo.stdout:  # until the banner: every child has started
            if "Press Ctrl-C" in line:
                break
        children = _children(demo.pid)
        assert len(children) == 3  # hub, simulator, agent

        demo.send_signal(signum)
        # The launcher's stop is bounded at 10 s a group (agents, simulators, hub).
        code = demo.wait(40)
        assert code == (-signal.SIGKILL if signum == signal.SIGKILL else 0)
        poll_until(lambda: not _alive(children), 30, f"children gone after {signum.name}")
    finally:
        if demo.poll() is None:
            demo.kill()
            demo.wait()
        if demo.stdout is not None:
            demo.stdout.close()


PYTEST_STARTS_A_FLEET = """
from pathlib import Path

from tests.support.processes import running_fleet


def test_fleet_until_killed(tmp_path: Path) -> None:
    with running_fleet(tmp_path, vehicles=1):
        Path({pid_file!r}).write_text("started")
        Path({pid_file!r}).with_suffix(".never").read_text()  # blocks: a FIFO nobody opens
"""


def test_no_child_outlives_a_killed_pytest(tmp_path: Path) -> None:
    """The fixtures start fleets through LocalFleet; pytest killed (-9) mid-test must not
    leave its hub, simulator and agent behind."""
    marker = tmp_path / "started.txt"
    os.mkfifo(marker.with_suffix(".never"))
    test_file = tmp_path / "test_killed.py"
    test_file.write_text(PYTEST_STARTS_A_FLEET.format(pid_file=str(marker)))
    root = Path(__file__).resolve().parents[2]
    runner = subprocess.Popen(
        [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", str(test_file)],
        cwd=root,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    try:
        poll_until(marker.exists, 60, "the fleet started inside pytest")
        children = _children(runner.pid)
        assert len(children) == 3
        runner.kill()
        runner.wait(10)
        poll_until(lambda: not _alive(children), 30, "the killed pytest's children gone")
    finally:
        if runner.poll() is None:
            runner.kill()
            runner.wait()
