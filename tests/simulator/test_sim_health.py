"""`python -m simulator.health`: the simulator image's health check, against a real
simulator, a closed port and a listener that never speaks MAVLink."""

from __future__ import annotations

import socket
import subprocess
import sys

from simulator import ListenAddress, SimulatorConfig
from simulator.health import heartbeat_from
from tests.support.simulators import REPO_ROOT, SYSID, free_port, serving


def test_a_ticking_simulator_is_healthy() -> None:
    config = SimulatorConfig(listen=ListenAddress("tcp", "127.0.0.1", 0), system_id=SYSID)
    with serving(config) as (_server, address):
        done = subprocess.run(
            [sys.executable, "-m", "simulator.health", f"tcp:0.0.0.0:{address.port}"],
            capture_output=True,
            text=True,
            timeout=30,
            cwd=REPO_ROOT,
            check=False,
        )
    assert done.returncode == 0, done.stderr
    assert "sends HEARTBEATs" in done.stdout


def test_nothing_listening_is_unhealthy_with_the_reason() -> None:
    port = free_port()
    done = subprocess.run(
        [sys.executable, "-m", "simulator.health", f"tcp:127.0.0.1:{port}"],
        capture_output=True,
        text=True,
        timeout=30,
        cwd=REPO_ROOT,
        check=False,
    )
    assert done.returncode == 1
    assert "unhealthy" in done.stderr
    assert "Connection refused" in done.stderr


def test_a_listener_that_sends_no_heartbeat_is_unhealthy() -> None:
    with socket.create_server(("127.0.0.1", 0)) as silent:
        port = silent.getsockname()[1]
        problem = heartbeat_from(ListenAddress("tcp", "127.0.0.1", port), timeout_s=0.5)
    assert problem == f"no HEARTBEAT from tcp:127.0.0.1:{port} within 0.5 s"


def test_a_bad_address_is_a_usage_error() -> None:
    done = subprocess.run(
        [sys.executable, "-m", "simulator.health", "serial:/dev/ttyS0"],
        capture_output=True,
        text=True,
        timeout=30,
        cwd=REPO_ROOT,
        check=False,
    )
    assert done.returncode == 2
    assert "expected tcp:HOST:PORT" in done.stderr
