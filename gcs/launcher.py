"""Start and stop a local fleet (hub, simulators, agents) as separate processes.

`gcs demo` uses this, and so do the integration tests, so both exercise the same path.
"""

from __future__ import annotations

import contextlib
import ctypes
import hmac
import json
import logging
import os
import secrets
import signal
import socket
import subprocess
import sys
import time
import urllib.error
import urllib.request
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import IO

from common.addresses import WILDCARDS, is_loopback
from common.geodesy import LocalFrame
from gcs.demo_lidars import DEMO_LIDARS

log = logging.getLogger(__name__)

PR_SET_PDEATHSIG = 1  # linux/prctl.h

# ArduPilot's SITL home (CMAC, Canberra): a place every ArduPilot developer knows.
DEFAULT_HOME = (-35.363262, 149.165237, 584.0)
VEHICLE_SPACING_M = 15.0
# The agents' MAVLink system id (the agent's own default, given explicitly so that the
# vehicles' setup below names the same one).
AGENT_SYSTEM_ID = 254
# PX4's COM_RCL_EXCEPT with bit 1 set: Hold is exempt from the manual-control-loss
# failsafe (the agent refuses manual control without it).
PX4_RCL_EXCEPT_HOLD = 1 << 1


def free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return int(probe.getsockname()[1])


@dataclass(frozen=True)
class FleetPlan:
    vehicles: int = 3
    host: str = "127.0.0.1"  # where the hub listens; the fleet's own links use loopback
    port: int = 8000
    data_dir: Path = Path("data")
    speedup: float = 1.0
    admin_password: str = field(default_factory=lambda: secrets.token_urlsafe(12))
    # Each vehicle's agent token is derived from this, so the plan stays one value.
    secret: str = field(default_factory=lambda: secrets.token_urlsafe(24))
    home: tuple[float, float, float] = DEFAULT_HOME
    telemetry_rate_hz: float = 10.0
    # Per vehicle, by index: the simulator's --frame ("quad", "rover") and --autopilot
    # ("ardupilot", "px4"); vehicles beyond a tuple's end are ArduPilot quads.
    frames: tuple[str, ...] = ()
    autopilots: tuple[str, ...] = ()
    # Each simulator fits a 2-D LIDAR (its bytes on a TCP port) and each agent relays it.
    lidars: bool = False
    # Which LIDAR they fit: a name of `DEMO_LIDARS` (its wire format in the simulator, its
    # model and scan mode in the agent, so that the agent's real parser reads it).
    lidar: str = "ydlidar"
    # Each simulator serves its camera's photos (a synthetic ground laid around ``home``,
    # the same for all) and each agent uploads them; the value is the agents'
    # --camera-model (sensor mm, image px, focal mm), None for no cameras.
    camera_model: str | None = None
    # Each ArduPilot vehicle is set up for this GCS as its owner would set up a real
    # aircraft (docs/operator.md, "Flying by hand"): SYSID_MYGCS = the agent's id, so that the
    # autopilot takes the agent's stick input and counts its heartbeats for the GCS
    # failsafe. The simulator keeps ArduPilot's default, 255, which is what a vehicle not
    # yet set up has; False leaves it there. (PX4 checks no sender id: its
    # COM_RC_IN_MODE default already lets MAVLink stick input in; but COM_RCL_EXCEPT = 2
    # exempts Hold from its manual-control-loss failsafe, so that the agent's deadman
    # hold stays a hold, where PX4's default 0 returns home.)
    gcs_configured: bool = True

    @property
    def local_host(self) -> str:
        """How processes on this machine reach the hub: loopback, unless the hub
        listens on one address only (not a wildcard)."""
        if self.host in WILDCARDS or is_loopback(self.host):
            return "127.0.0.1"
        return f"[{self.host}]" if ":" in self.host else self.host

    @property
    def hub_http(self) -> str:
        return f"http://{self.local_host}:{self.port}"

    @property
    def hub_ws(self) -> str:
        return f"ws://{self.local_host}:{self.port}"

    @property
    def public_http(self) -> str:
        """The address to give a browser on another machine (a placeholder where the hub
        listens on every interface, as it cannot know which one the tablet sees)."""
        if self.host in WILDCARDS:
            return f"http://<this machine's address>:{self.port}"
        return self.hub_http

    @staticmethod
    def vehicle_id(index: int) -> str:
        return f"sim_{index + 1}"

    def agent_token(self, index: int) -> str:
        digest = hmac.new(self.secret.encode(), self.vehicle_id(index).encode(), "sha256")
        return "gcs_v_" + digest.hexdigest()

    @classmethod
    def reusing_secrets(cls, data_dir: Path, **values: object) -> FleetPlan:
        """A plan whose admin password and tokens persist in the data folder, so a demo
        restarted on the same data logs in with the same password."""
        path = data_dir / "demo-secrets.json"
        if path.is_file():
            stored = json.loads(path.read_text())
            return cls(data_dir=data_dir, **values, **stored)  # type: ignore[arg-type]
        plan = cls(data_dir=data_dir, **values)  # type: ignore[arg-type]
        data_dir.mkdir(mode=0o700, parents=True, exist_ok=True)
        path.touch(mode=0o600)
        path.write_text(json.dumps({"admin_password": plan.admin_password, "secret": plan.secret}))
        return plan

    def vehicle_sim_args(self, index: int) -> list[str]:
        """The simulator options that make vehicle ``index`` what the plan says it is."""
        args: list[str] = []
        if index < len(self.frames):
            args += ["--frame", self.frames[index]]
        if index < len(self.autopilots):
            args += ["--autopilot", self.autopilots[index]]
        autopilot = self.autopilots[index] if index < len(self.autopilots) else "ardupilot"
        if self.gcs_configured and autopilot == "ardupilot":
            args += ["--param", f"SYSID_MYGCS={AGENT_SYSTEM_ID}"]
        if self.gcs_configured and autopilot == "px4":
            args += ["--param", f"COM_RCL_EXCEPT={PX4_RCL_EXCEPT_HOLD}"]
        return args

    def vehicle_home(self, index: int) -> tuple[float, float, float]:
        """Homes in a row, a few metres apart, so the vehicles do not share a spot."""
        lat, lon, alt = self.home
        lat, lon = LocalFrame(lat, lon, alt).to_geo(index * VEHICLE_SPACING_M, 0.0)
        return lat, lon, alt


def end_with_parent(signum: int = signal.SIGTERM) -> Callable[[], None] | None:
    """A ``preexec_fn`` by which a child gets ``signum`` when the thread that started it
    ends, however it ends (Linux's PR_SET_PDEATHSIG, kept across exec). The child's own
    SIGTERM handling then stops it cleanly. None where the kernel has no such thing."""
    if not sys.platform.startswith("linux"):
        return None
    prctl = ctypes.CDLL(None, use_errno=True).prctl
    parent = os.getpid()

    def arm() -> None:  # runs in the child, between fork and exec
        prctl(PR_SET_PDEATHSIG, signum, 0, 0, 0)
        if os.getppid() != parent:  # the parent died before the line above: too late
            os.kill(os.getpid(), signum)

    return arm


@dataclass
class ManagedProcess:
    name: str
    process: subprocess.Popen[bytes]
    log_path: Path
    log_file: IO[bytes]


class LocalFleet:
    """The processes of one local fleet; stop() ends agents, then simulators, then the hub."""

    def __init__(self, plan: FleetPlan) -> None:
        self.plan = plan
        self.log_dir = plan.data_dir / "logs"
        self.processes: list[ManagedProcess] = []
        self.sim_ports: dict[int, int] = {}  # by vehicle index, to restart an agent
        self.lidar_ports: dict[int, int] = {}
        self.camera_ports: dict[int, int] = {}
        # The hub address an agent dials instead of the plan's, by vehicle index: a test
        # puts a proxy it can cut between one agent and the hub.
        self.agent_hubs: dict[int, str] = {}

    def vehicle_id(self, index: int) -> str:
        return self.plan.vehicle_id(index)

    def sim_address(self, index: int) -> str:
        """Where vehicle ``index``'s simulator takes MAVLink clients: its agent, and any
        ground station beside it (it serves any number, as SITL's port 5760 does)."""
        return f"tcp:127.0.0.1:{self.sim_ports[index]}"

    def start(self, hub_env: dict[str, str] | None = None) -> None:
        # The data folder and the logs are the operator's alone (0700 folders, 0600 files).
        self.plan.data_dir.mkdir(mode=0o700, parents=True, exist_ok=True)
        self.log_dir.mkdir(mode=0o700, parents=True, exist_ok=True)
        self.start_hub(hub_env)
        for index in range(self.plan.vehicles):
            self.start_vehicle(index)

    def start_hub(self, hub_env: dict[str, str] | None = None) -> None:
        plan = self.plan
        tokens = ",".join(
            f"{plan.vehicle_id(i)}={plan.agent_token(i)}" for i in range(plan.vehicles)
        )
        env = {
            # A local demo on plain HTTP: no Secure cookies, no production secret checks.
            "GCS_ENVIRONMENT": "development",
            "GCS_ADMIN_PASSWORD": plan.admin_password,
        }
        if not is_loopback(plan.host):
            # Asked for with --host: the hub still warns loudly at start.
            env["GCS_ALLOW_DEVELOPMENT_ON_NETWORK"] = "true"
        if tokens:  # a hub alone (no vehicles) has none to enrol
            env["GCS_AGENT_TOKENS"] = tokens
        if plan.speedup > 1.0:  # formations fly in the simulators' seconds
            env["GCS_FLEET_SPEEDUP"] = str(plan.speedup)
        self.spawn(
            "hub",
            [
                "hub",
                "--host",
                plan.host,
                "--port",
                str(plan.port),
                "--data-dir",
                str(plan.data_dir),
            ],
            {**env, **(hub_env or {})},
        )

    def kill(self, name: str) -> None:
        """End one process at once (SIGKILL: no flush, no goodbye), as a crash would."""
        for managed in [m for m in self.processes if m.name == name]:
            managed.process.kill()
            managed.process.wait()
            managed.log_file.close()
            self.processes.remove(managed)

    def start_vehicle(self, index: int) -> None:
        sim_port = free_port()
        self.sim_ports[index] = sim_port
        lat, lon, alt = self.plan.vehicle_home(index)
        lidar: list[str] = []
        if self.plan.lidars:
            self.lidar_ports[index] = free_port()
            lidar = [
                "--lidar",
                f"tcp:127.0.0.1:{self.lidar_ports[index]}",
                "--lidar-format",
                DEMO_LIDARS[self.plan.lidar].wire,
            ]
        camera: list[str] = []
        if self.plan.camera_model is not None:
            self.camera_ports[index] = free_port()
            ground = ",".join(f"{value:.7f}" for value in self.plan.home)
            camera = ["--camera", f"tcp:127.0.0.1:{self.camera_ports[index]}", "--ground", ground]
        self.spawn(
            f"sim_{index + 1}",
            [
                "sim",
                "--listen",
                self.sim_address(index),
                "--system-id",
                str(index + 1),
                "--home",
                f"{lat:.7f},{lon:.7f},{alt:.1f}",
                "--speedup",
                str(self.plan.speedup),
                *self.plan.vehicle_sim_args(index),
                *lidar,
                *camera,
            ],
        )
        self.start_agent(index, sim_port)

    def start_agent(self, index: int, sim_port: int) -> None:
        """The agent of vehicle ``index``, to its flight controller on ``sim_port``."""
        self.spawn(
            f"agent_{index + 1}",
            [
                "agent",
                "--fcu",
                f"tcp:127.0.0.1:{sim_port}",
                "--hub",
                self.agent_hubs.get(index, self.plan.hub_ws),
                "--vehicle-id",
                self.vehicle_id(index),
                "--source-system",
                str(AGENT_SYSTEM_ID),
                "--telemetry-rate-hz",
                str(self.plan.telemetry_rate_hz),
                # Each simulated vehicle keeps an onboard .tlog, as a real one would.
                "--tlog-dir",
                str(self.plan.data_dir / "onboard" / self.vehicle_id(index)),
                # ...and keeps what the hub has not stored on disk, through hub outages.
                "--outbox-dir",
                str(self.plan.data_dir / "onboard" / self.vehicle_id(index)),
                *(
                    [
                        "--lidar",
                        f"tcp://127.0.0.1:{self.lidar_ports[index]}",
                        "--lidar-model",
                        DEMO_LIDARS[self.plan.lidar].model,
                        "--lidar-scan-mode",
                        str(DEMO_LIDARS[self.plan.lidar].scan_mode),
                    ]
                    if index in self.lidar_ports
                    else []
                ),
                *(
                    [
                        "--camera",
                        f"sim+http://127.0.0.1:{self.camera_ports[index]}",
                        "--camera-model",
                        self.plan.camera_model or "",
                    ]
                    if index in self.camera_ports
                    else []
                ),
            ],
            {"GCS_AGENT_TOKEN": self.plan.agent_token(index)},
        )

    def spawn(self, name: str, args: list[str], env: dict[str, str] | None = None) -> None:
        log_path = self.log_dir / f"{name}.log"
        log_path.touch(mode=0o600)
        log_path.chmod(0o600)  # also one written before logs were private
        log_file = log_path.open("ab")
        process = subprocess.Popen(
            [sys.executable, "-m", "gcs", *args],
            stdin=subprocess.DEVNULL,
            stdout=log_file,
            stderr=subprocess.STDOUT,
            env={**os.environ, **(env or {})},
            # Own session: a Ctrl-C reaches only the launcher, which stops the
            # children in order (agents before the hub, so the hub stores everything).
            start_new_session=True,
            # ...and should the launcher die without stopping them (SIGKILL, a crash),
            # they end too instead of living on as orphans.
            preexec_fn=end_with_parent(),
        )
        self.processes.append(ManagedProcess(name, process, log_path, log_file))

    def wait_until_ready(self, timeout_s: float = 30.0) -> None:
        """Until the hub answers its health check; raises if a process died first."""
        deadline = time.monotonic() + timeout_s
        while True:
            self.check_alive()
            try:
                with urllib.request.urlopen(f"{self.plan.hub_http}/api/v1/health", timeout=2):
                    return
            except (urllib.error.URLError, ConnectionError, TimeoutError):
                # TimeoutError: a hub still starting on a busy machine answers late.
                if time.monotonic() > deadline:
                    raise TimeoutError(f"hub not ready after {timeout_s:.0f} s") from None
                time.sleep(0.1)  # nothing to wait on but the port opening

    def check_alive(self) -> None:
        for managed in self.processes:
            code = managed.process.poll()
            if code is not None:
                raise RuntimeError(
                    f"{managed.name} exited with code {code}; see {managed.log_path}"
                )

    def stop(self, timeout_s: float = 10.0) -> None:
        for group in ("agent", "sim", "hub"):
            members = [m for m in self.processes if m.name.startswith(group)]
            for managed in members:
                if managed.process.poll() is None:
                    managed.process.send_signal(signal.SIGTERM)
            for managed in members:
                try:
                    managed.process.wait(timeout_s)
                except subprocess.TimeoutExpired:
                    log.warning("%s did not stop in %.0f s; killing it", managed.name, timeout_s)
                    managed.process.kill()
                    managed.process.wait()
                managed.log_file.close()
        self.processes.clear()

    def __enter__(self) -> LocalFleet:
        return self

    def __exit__(self, *exc: object) -> None:
        with contextlib.suppress(Exception):
            self.stop()
