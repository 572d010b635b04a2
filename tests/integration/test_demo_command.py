"""`gcs demo` starts the whole fleet as processes and Ctrl-C stops every one of them."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
from pathlib import Path

import httpx
import pytest

from gcs.launcher import free_port
from tests.helpers import FleetWatcher, access_token

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
