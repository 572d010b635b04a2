"""An agent whose pymavlink has been slimmed (`python -m vehicle_agents.slim_install`)
still names, connects and reports a vehicle: it never needed what was taken out."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest

from gcs.launcher import end_with_parent, free_port
from tests.support.watcher import FleetWatcher, ready
from vehicle_agents.config import default_vehicle_id
from vehicle_agents.slim_install import installed_pymavlink, slim, unneeded_files

pytestmark = pytest.mark.integration

GCS_AGENT = str(Path(sys.executable).with_name("gcs-agent"))


@pytest.fixture
def slim_pymavlink(tmp_path: Path) -> Path:
    """A copy of the installed pymavlink, slimmed; returns the folder to put on the path."""
    site = tmp_path / "site"
    shutil.copytree(installed_pymavlink(), site / "pymavlink")
    before = sum(1 for _ in (site / "pymavlink").rglob("*"))
    freed = slim(site / "pymavlink")
    assert freed > 50e6  # most of the 90 MB of other dialects, bytecode included
    assert not list(unneeded_files(site / "pymavlink"))
    assert sum(1 for _ in (site / "pymavlink").rglob("*")) < before
    assert (site / "pymavlink" / "dialects" / "v20" / "ardupilotmega.py").exists()
    assert not (site / "pymavlink" / "dialects" / "v20" / "all.py").exists()
    return site


@pytest.fixture
def simulator_port(tmp_path: Path) -> Iterator[int]:
    port = free_port()
    with (tmp_path / "sim.log").open("wb") as log:
        sim = subprocess.Popen(
            [sys.executable, "-m", "gcs", "sim", "--listen", f"tcp:127.0.0.1:{port}"],
            stdout=log,
            stderr=subprocess.STDOUT,
            preexec_fn=end_with_parent(),
        )
        try:
            yield port
        finally:
            sim.terminate()
            sim.wait(10)


def test_the_agent_runs_on_a_slimmed_pymavlink(
    slim_pymavlink: Path,
    simulator_port: int,
    hub: str,
    admin_token: str,
    enrol: Callable[[str], str],
    tmp_path: Path,
) -> None:
    env = {k: v for k, v in os.environ.items() if not k.startswith(("GCS_AGENT_", "MAVLINK"))}
    env["PYTHONPATH"] = str(slim_pymavlink)  # ahead of the installed pymavlink
    fcu = f"tcp:127.0.0.1:{simulator_port}"
    loaded = subprocess.run(
        [sys.executable, "-c", "import pymavlink; print(pymavlink.__file__)"],
        env=env,
        capture_output=True,
        text=True,
        check=True,
    )
    assert loaded.stdout.startswith(str(slim_pymavlink))
    printed = subprocess.run(
        [GCS_AGENT, "--print-id", "--fcu", fcu], env=env, capture_output=True, text=True
    )
    assert printed.returncode == 0, printed.stderr
    vehicle_id = printed.stdout.strip()
    assert vehicle_id == default_vehicle_id("multirotor")

    env["GCS_AGENT_TOKEN"] = enrol(vehicle_id)
    with (tmp_path / "agent.log").open("wb") as log:
        agent = subprocess.Popen(
            [GCS_AGENT, "--fcu", fcu, "--hub", hub.replace("http://", "ws://")],
            env=env,
            stdout=log,
            stderr=subprocess.STDOUT,
            preexec_fn=end_with_parent(),
        )
        try:
            with FleetWatcher(hub, admin_token) as watcher:
                # A position, a battery and a home: the messages decode as they did.
                watcher.wait_until(ready(vehicle_id), 30, f"{vehicle_id} connected, ready")
                assert watcher.state(vehicle_id)["mode"]
        finally:
            agent.terminate()
            agent.wait(10)
