"""`gcs-agent --health`: the agent image's health check reads what the running agent
writes (--health-file), against a real simulator and a hub that is not there."""

from __future__ import annotations

import json
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from tests.support.simulators import free_port, simulator_process
from vehicle_agents.health import STALE_AFTER_S, HealthFile, check

ROOT = Path(__file__).resolve().parents[2]
pytestmark = pytest.mark.integration
AGENT = [sys.executable, "-c", "import sys; from vehicle_agents.cli import main; sys.exit(main())"]


def _health(health_file: Path) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [*AGENT, "--health", "--health-file", str(health_file)],
        capture_output=True,
        text=True,
        timeout=60,
        cwd=ROOT,
        check=False,
    )


def test_a_running_agent_reports_each_link_and_a_stopped_one_is_unhealthy(
    tmp_path: Path,
) -> None:
    health_file = tmp_path / "health.json"
    assert _health(health_file).returncode == 1  # no agent yet
    hub_port = free_port()  # nothing listens there: the hub link stays down
    with simulator_process() as (fcu_port, _lines):
        agent = subprocess.Popen(
            [
                *AGENT,
                "--fcu",
                f"tcp:127.0.0.1:{fcu_port}",
                "--hub",
                f"ws://127.0.0.1:{hub_port}",
                "--token",
                "t" * 32,
                "--vehicle-id",
                "health_1",
                "--health-file",
                str(health_file),
            ],
            cwd=ROOT,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
        )
        try:
            # The agent writes the file once it has heard the flight controller.
            deadline = time.monotonic() + 30
            state: dict[str, object] = {}
            while not state.get("fcu"):
                assert time.monotonic() < deadline, "the agent wrote no health file in 30 s"
                assert agent.poll() is None, "the agent stopped"
                if health_file.exists():
                    state = json.loads(health_file.read_text())
                time.sleep(0.2)  # polling a file another process writes
            assert state["hub"] is False
            done = _health(health_file)
            assert done.returncode == 1
            assert "unhealthy: no link to the hub" in done.stderr
        finally:
            agent.send_signal(signal.SIGTERM)
            agent.wait(30)
    assert not health_file.exists(), "a stopped agent must not leave a healthy-looking file"


def test_fresh_and_both_links_up_is_healthy_and_a_stale_file_is_not(tmp_path: Path) -> None:
    path = tmp_path / "health.json"
    HealthFile(path, fcu_up=lambda: True, hub_up=lambda: True).write()
    done = _health(path)
    assert done.returncode == 0, done.stderr
    assert "healthy" in done.stdout
    written = json.loads(path.read_text())["written_at"]
    stale = check(path, now=written + STALE_AFTER_S + 1)
    assert stale is not None
    assert "the agent is stuck or stopped" in stale
    HealthFile(path, fcu_up=lambda: False, hub_up=lambda: False).write()
    assert check(path) == "no link to the flight controller or the hub"


@pytest.mark.parametrize("text", ["", "{", '{"fcu": true}'])
def test_a_damaged_file_is_unhealthy(tmp_path: Path, text: str) -> None:
    path = tmp_path / "health.json"
    path.write_text(text)
    problem = check(path)
    assert problem is not None
    assert problem.startswith(f"{path} is unreadable")


def test_health_without_a_health_file_names_the_setting() -> None:
    done = subprocess.run(
        [*AGENT, "--health"], capture_output=True, text=True, timeout=60, cwd=ROOT, check=False
    )
    assert done.returncode == 2
    assert "--health-file" in done.stderr
    assert "GCS_AGENT_HEALTH_FILE" in done.stderr
