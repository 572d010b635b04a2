"""A hub reachable from the network says so, and development mode (default passwords,
short tokens) does not go there unasked: `gcs hub` refuses, `gcs demo --host` warns."""

from __future__ import annotations

import os
import signal
import socket
import subprocess
import sys
from pathlib import Path

import httpx
import pytest
from pydantic import ValidationError

from backend.settings import HubSettings
from gcs.launcher import free_port

pytestmark = pytest.mark.integration


def _lan_address() -> str | None:
    """An address of this machine other than loopback, as a tablet on the LAN sees it."""
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as probe:
        try:
            probe.connect(("192.0.2.1", 9))  # no packet is sent: this only picks a route
        except OSError:
            return None
        address = str(probe.getsockname()[0])
    return None if address.startswith("127.") else address


def test_development_settings_refuse_an_address_beyond_loopback(tmp_path: Path) -> None:
    with pytest.raises(ValidationError, match="GCS_ALLOW_DEVELOPMENT_ON_NETWORK"):
        HubSettings(data_dir=tmp_path, environment="development", host="0.0.0.0")
    for host in ("127.0.0.1", "localhost", "::1"):
        HubSettings(data_dir=tmp_path, environment="development", host=host)
    HubSettings(
        data_dir=tmp_path,
        environment="development",
        host="0.0.0.0",
        allow_development_on_network=True,
    )


def _hub(tmp_path: Path, **env: str) -> subprocess.Popen[str]:
    return subprocess.Popen(
        [
            *(sys.executable, "-m", "gcs", "hub", "--host", "0.0.0.0"),
            *("--port", str(free_port()), "--data-dir", str(tmp_path)),
        ],
        env={**os.environ, "GCS_ENVIRONMENT": "development", **env},
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
    )


def test_gcs_hub_refuses_development_mode_on_the_network(tmp_path: Path) -> None:
    with _hub(tmp_path) as hub:
        output, _ = hub.communicate(timeout=60)
    assert hub.returncode == 2
    assert "refusing to listen on 0.0.0.0 in development mode" in output
    assert "Traceback" not in output


def test_gcs_hub_warns_loudly_when_development_mode_is_allowed_on_the_network(
    tmp_path: Path,
) -> None:
    with _hub(tmp_path, GCS_ALLOW_DEVELOPMENT_ON_NETWORK="true") as hub:
        assert hub.stdout is not None
        started = ""
        for line in hub.stdout:  # until uvicorn listens
            started += line
            if "Uvicorn running on" in line:
                break
        hub.send_signal(signal.SIGTERM)
        hub.communicate(timeout=30)
    assert "WARNING" in started
    assert "DEVELOPMENT MODE ON THE NETWORK (0.0.0.0:" in started
    assert "serving plain HTTP on 0.0.0.0" in started


def test_demo_host_lets_a_tablet_on_the_lan_reach_it_and_warns(tmp_path: Path) -> None:
    lan = _lan_address()
    if lan is None:
        pytest.skip("this machine has no address beyond loopback")
    port = free_port()
    demo = subprocess.Popen(
        [
            *(sys.executable, "-m", "gcs", "demo", "--vehicles", "1", "--host", "0.0.0.0"),
            *("--port", str(port), "--data-dir", str(tmp_path)),
        ],
        stdout=subprocess.PIPE,
        text=True,
    )
    try:
        assert demo.stdout is not None
        banner = ""
        for line in demo.stdout:
            banner += line
            if "Press Ctrl-C" in line:
                break
        assert "WARNING: listening on 0.0.0.0 with plain HTTP" in banner
        assert f"http://<this machine's address>:{port}/" in banner
        assert httpx.get(f"http://{lan}:{port}/api/v1/health").status_code == 200
        assert "DEVELOPMENT MODE ON THE NETWORK" in (tmp_path / "logs" / "hub.log").read_text()
        demo.send_signal(signal.SIGINT)
        assert demo.wait(30) == 0
    finally:
        if demo.poll() is None:
            demo.kill()
            demo.wait()
        if demo.stdout is not None:
            demo.stdout.close()
