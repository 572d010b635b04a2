"""Photos a camera uploads, and the hub's answer to them."""

from __future__ import annotations

import contextlib
import socket
import subprocess
import sys
from collections.abc import Iterator, Sequence
from pathlib import Path
from typing import Any

import httpx
from pymavlink import mavutil

from gcs.launcher import free_port
from simulator.config import DEFAULT_HOME
from tests.support.api import access_token, api_client
from tests.support.hub_server import running_hub
from tests.support.hubs import ADMIN_PASSWORD, hub_settings
from tests.support.processes import agent_process
from tests.support.waiting import poll_until

CAMERA_MODEL = "4.8,3.6,320,240,5.4"  # a small sensor and image: fast to render and send


GROUND_BELOW_M = 30.0


def _accepts(port: int) -> bool:
    try:
        socket.create_connection(("127.0.0.1", port), timeout=1).close()
    except OSError:
        return False
    return True


@contextlib.contextmanager
def camera_vehicle(
    folder: Path,
    vehicle: str,
    sim_args: Sequence[str],
    camera: str,
    *,
    sim_camera_model: bool = True,
) -> Iterator[tuple[httpx.Client, Any, Path]]:
    """A hub, a simulator with ``sim_args`` (its photo server on a free port given as
    ``{camera_port}``, there and in ``camera``; rendering with `CAMERA_MODEL` unless
    ``sim_camera_model`` is off) and an agent with ``--camera camera``; yields the API, a
    second GCS's connection to the simulator, and the agent's log."""
    hub_dir, logs = folder / "hub", folder / "logs"
    logs.mkdir(parents=True)
    sim_port, camera_port = free_port(), free_port()
    lat, lon, alt = DEFAULT_HOME.lat, DEFAULT_HOME.lon, DEFAULT_HOME.alt
    with (
        running_hub(hub_settings(hub_dir)) as hub,
        api_client(hub, access_token(hub, "admin", ADMIN_PASSWORD)) as api,
        (logs / "sim.log").open("wb") as sim_log,
    ):
        enrolled = api.post(f"/api/v1/vehicles/{vehicle}/agent-tokens")
        assert enrolled.status_code == 201, enrolled.text
        sim = subprocess.Popen(
            [
                *(sys.executable, "-m", "gcs", "sim"),
                *("--listen", f"tcp:127.0.0.1:{sim_port}"),
                *(arg.format(camera_port=camera_port) for arg in sim_args),
                *(("--camera-model", CAMERA_MODEL) if sim_camera_model else ()),
                f"--ground={lat},{lon},{alt - GROUND_BELOW_M}",
            ],
            stdout=sim_log,
            stderr=subprocess.STDOUT,
        )
        try:
            poll_until(lambda: _accepts(sim_port), 60, "the simulator listening")
            with agent_process(
                hub,
                enrolled.json()["token"],
                vehicle,
                sim_port,
                logs,
                extra_args=[
                    *("--camera", camera.format(camera_port=camera_port)),
                    *("--camera-model", CAMERA_MODEL),
                    *("--photo-dir", str(folder / "onboard")),
                ],
            ):
                fcu = mavutil.mavlink_connection(
                    f"tcp:127.0.0.1:{sim_port}", source_system=250, source_component=190
                )
                try:
                    fcu.wait_heartbeat(timeout=30)
                    poll_until(
                        lambda: api.get(f"/api/v1/vehicles/{vehicle}").status_code == 200,
                        60,
                        f"{vehicle} connected to the hub",
                    )
                    yield api, fcu, logs / f"{vehicle}.log"
                finally:
                    fcu.close()
        finally:
            sim.terminate()
            sim.wait(10)
