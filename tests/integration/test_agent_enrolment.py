"""An onboard computer's first connection, as docs/deployer.md tells it: `gcs-agent --print-id`
names the vehicle before it is enrolled (no token yet), an admin enrols that id, and the
agent, started without --vehicle-id, connects under it."""

from __future__ import annotations

import os
import subprocess
import sys
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest

from gcs.launcher import end_with_parent, free_port
from tests.support.watcher import FleetWatcher, connected
from vehicle_agents.config import default_vehicle_id

pytestmark = pytest.mark.integration

SIM = [sys.executable, "-m", "gcs", "sim"]
GCS_AGENT = str(Path(sys.executable).with_name("gcs-agent"))  # the agent-only command


def _without_agent_settings() -> dict[str, str]:
    return {k: v for k, v in os.environ.items() if not k.startswith("GCS_AGENT_")}


@pytest.fixture
def simulated_rover(tmp_path: Path) -> Iterator[int]:
    """A simulated ArduRover on loopback TCP; yields its port."""
    port = free_port()
    with (tmp_path / "sim.log").open("wb") as log:
        sim = subprocess.Popen(
            [*SIM, "--listen", f"tcp:127.0.0.1:{port}", "--frame", "rover", "--speedup", "4"],
            stdout=log,
            stderr=subprocess.STDOUT,
            preexec_fn=end_with_parent(),
        )
        try:
            yield port
        finally:
            sim.terminate()
            sim.wait(10)


def test_print_id_names_the_vehicle_before_enrolment(
    simulated_rover: int,
    hub: str,
    admin_token: str,
    enrol: Callable[[str], str],
    tmp_path: Path,
) -> None:
    fcu = f"tcp:127.0.0.1:{simulated_rover}"
    printed = subprocess.run(
        [GCS_AGENT, "--print-id", "--fcu", fcu],
        env=_without_agent_settings(),  # not enrolled yet: no token anywhere
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert printed.returncode == 0, printed.stderr
    vehicle_id = printed.stdout.strip()
    # The heartbeat's type and this machine's id, as the agent names itself.
    assert vehicle_id == default_vehicle_id("rover")
    assert vehicle_id.startswith("rover_")

    token = enrol(vehicle_id)
    with (tmp_path / "agent.log").open("wb") as log:
        agent = subprocess.Popen(
            [GCS_AGENT, "--fcu", fcu, "--hub", hub.replace("http://", "ws://")],
            env={**_without_agent_settings(), "GCS_AGENT_TOKEN": token},
            stdout=log,
            stderr=subprocess.STDOUT,
            preexec_fn=end_with_parent(),
        )
        try:
            with FleetWatcher(hub, admin_token) as watcher:
                watcher.wait_until(connected(vehicle_id), 30, f"{vehicle_id} connected")
        finally:
            agent.terminate()
            agent.wait(10)


def test_print_id_with_a_chosen_id_needs_no_flight_controller() -> None:
    printed = subprocess.run(
        [GCS_AGENT, "--print-id", "--fcu", "tcp:127.0.0.1:9", "--vehicle-id", "survey_7"],
        env=_without_agent_settings(),
        capture_output=True,
        text=True,
        timeout=30,
    )
    assert (printed.returncode, printed.stdout) == (0, "survey_7\n")


@pytest.mark.parametrize("fcu", ["tcp:127.0.0.1:{port}", "/dev/ttyGCS-absent-{port}"])
def test_print_id_without_a_flight_controller_gives_up_saying_why(
    fcu: str, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """Nothing answers (a closed port, a serial device that is not there): --print-id
    stops retrying after its wait, says what to check, and exits 1."""
    from vehicle_agents import cli
    from vehicle_agents.config import load_agent_settings

    monkeypatch.setattr(cli, "PRINT_ID_TIMEOUT_S", 1.5)  # 30 s on a board
    for name in set(os.environ) - set(_without_agent_settings()):
        monkeypatch.delenv(name)
    url = fcu.format(port=free_port())
    settings = load_agent_settings({"fcu": url}, None, require_token=False)
    assert cli.print_id(settings, "gcs-agent") == 1
    said = capsys.readouterr().err
    assert f"gcs-agent: no heartbeat from {url} within 1.5 s" in said
    assert "Check --fcu, or choose an id with --vehicle-id." in said
