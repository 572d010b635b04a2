"""Agent footprint: memory and CPU of the vehicle agent at 200 MAVLink messages/s in,
side by side with MAVProxy on the same stream (DESIGN.md: <= 60 MB RSS, <= 5 % of a core).

    python3 -m venv /tmp/gcs-bench && /tmp/gcs-bench/bin/pip install '.[bench]'
    .venv/bin/python bench/bench_agent.py --mavproxy /tmp/gcs-bench/bin/mavproxy.py
    # options: --seconds 30 (measured), --warmup 8

MAVProxy comes from the ``bench`` extra, which is not part of ``dev`` (CI never installs
it: on Linux x86-64 it pulls numpy, matplotlib, OpenCV and VTK, about 1 GB). Install it in
a venv of its own, as above, not in the agent's: pymavlink.mavutil imports numpy whenever
it can, and in the agent that alone costs some 13 MB of RSS that a vehicle's onboard
computer, with the agent's own dependencies, does not pay. The benchmark warns if numpy is
importable by the agent's interpreter (the one running the benchmark).

What runs, all on loopback, in one go:

- a MAVLink source standing in for a flight controller on TCP (as SITL's 5760): every
  client gets the same 200 messages/s, a realistic ArduCopter mix (ATTITUDE at 50 Hz,
  RAW_IMU, GLOBAL_POSITION_INT, VFR_HUD, SYS_STATUS, GPS_RAW_INT, HEARTBEAT, ...). It
  acknowledges commands and answers parameter and mission requests, but keeps its rates
  whatever is asked, so every client sees exactly the same load;
- a real hub (``gcs hub`` with a temporary data folder, GCS_ENVIRONMENT=development and
  the agents' tokens in GCS_AGENT_TOKENS, as ``gcs demo`` provisions it);
- ``gcs agent`` connected to the source and the hub;
- a second agent that also forwards everything to a GCS (``--mavlink-forward udpout:``);
- ``mavproxy.py --master tcp:... --out udpout:... --daemon --no-state`` (headless, no
  logs written), the usual way to share a flight controller with another GCS.

After a warm-up, each process (with any children) is sampled once a second from /proc:
RSS, and CPU time over wall time (100 % is one core fully busy). The two UDP sinks count
what reached them, which shows the forwarders kept up. Prints a table; asserts nothing.
If MAVProxy is missing or will not run, the table says why and the agents are still
measured.
"""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import importlib.util
import json
import math
import os
import shutil
import signal
import socket
import statistics
import subprocess
import sys
import tempfile
import threading
import time
import urllib.error
import urllib.request
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from gcs.launcher import free_port

# ArduCopter-like rates (Hz); they add up to 200 messages/s.
STREAM_HZ: dict[str, float] = {
    "ATTITUDE": 50,
    "RAW_IMU": 25,
    "GLOBAL_POSITION_INT": 25,
    "VFR_HUD": 20,
    "LOCAL_POSITION_NED": 20,
    "SERVO_OUTPUT_RAW": 10,
    "RC_CHANNELS": 10,
    "SCALED_PRESSURE": 10,
    "GPS_RAW_INT": 10,
    "SYS_STATUS": 5,
    "BATTERY_STATUS": 5,
    "EKF_STATUS_REPORT": 5,
    "VIBRATION": 3,
    "SYSTEM_TIME": 1,
    "HEARTBEAT": 1,
}
RATE = sum(STREAM_HZ.values())
TICK_S = 0.005
PARAMS = {f"BENCH_P{i:02d}": float(i) for i in range(40)} | {"SYSID_THISMAV": 1.0}
MAX_CLIENT_BACKLOG = 1 << 20  # bytes queued for a client that does not read: drop beyond
VEHICLE_ID = "bench_agent"
FORWARDING_VEHICLE_ID = "bench_forwarding"
AGENT_BAR = (60.0, 5.0)  # MB RSS, % of one core
CLOCK_TICKS = os.sysconf("SC_CLK_TCK")
PAGE_KB = os.sysconf("SC_PAGE_SIZE") // 1024


# -- the MAVLink source ------------------------------------------------------------


def build(kind: str, t: float, boot: float) -> Any:
    """One message of ``kind`` with values that move, as a vehicle in flight sends them."""
    ms = int((t - boot) * 1000) & 0xFFFFFFFF  # time_boot_ms
    us = int((t - boot) * 1e6)  # time_usec (uint64)
    s = math.sin(t)
    m = mavlink2
    match kind:
        case "HEARTBEAT":
            return m.MAVLink_heartbeat_message(
                m.MAV_TYPE_QUADROTOR,
                m.MAV_AUTOPILOT_ARDUPILOTMEGA,
                m.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED | m.MAV_MODE_FLAG_SAFETY_ARMED,
                5,
                m.MAV_STATE_ACTIVE,
                3,
            )
        case "ATTITUDE":
            return m.MAVLink_attitude_message(ms, 0.05 * s, -0.03 * s, 1.2 + 0.1 * s, 0, 0, 0.01)
        case "RAW_IMU":
            return m.MAVLink_raw_imu_message(us, 10, -5, -1000, 1, 2, 3, 200, 100, -400)
        case "GLOBAL_POSITION_INT":
            return m.MAVLink_global_position_int_message(
                ms, int(-353632620 + 500 * s), 1491652370, 614000, 30000, 150, 20, -10, 9000
            )
        case "VFR_HUD":
            return m.MAVLink_vfr_hud_message(0.0, 1.8, 90, 45, 614.0, -0.1)
        case "LOCAL_POSITION_NED":
            return m.MAVLink_local_position_ned_message(ms, 5.0 * s, 2.0, -30.0, 1.5, 0.2, -0.1)
        case "SERVO_OUTPUT_RAW":
            return m.MAVLink_servo_output_raw_message(us & 0xFFFFFFFF, 0, *([1500] * 8))
        case "RC_CHANNELS":
            return m.MAVLink_rc_channels_message(ms, 16, *([1500] * 18), 255)
        case "SCALED_PRESSURE":
            return m.MAVLink_scaled_pressure_message(ms, 1005.2, 0.1, 2150)
        case "GPS_RAW_INT":
            return m.MAVLink_gps_raw_int_message(
                us, 3, -353632620, 1491652370, 614000, 80, 120, 180, 9000, 14
            )
        case "SYS_STATUS":
            sensors = 0x0321FC3F
            return m.MAVLink_sys_status_message(
                sensors, sensors, sensors, 250, 15800, 1250, 78, 0, 0, 0, 0, 0, 0
            )
        case "BATTERY_STATUS":
            return m.MAVLink_battery_status_message(
                0, 1, 1, 3000, [3950] * 4 + [65535] * 6, 1250, 2100, 23000, 78
            )
        case "EKF_STATUS_REPORT":
            return m.MAVLink_ekf_status_report_message(0x3FF, 0.1, 0.1, 0.05, 0.02, 0.0)
        case "VIBRATION":
            return m.MAVLink_vibration_message(us, 4.0, 4.5, 6.0, 0, 0, 0)
        case "SYSTEM_TIME":
            return m.MAVLink_system_time_message(int(t * 1e6), ms)
    raise ValueError(kind)


@dataclass
class Client:
    writer: asyncio.StreamWriter
    encoder: Any = field(
        default_factory=lambda: mavlink2.MAVLink(None, srcSystem=1, srcComponent=1)
    )
    parser: Any = field(default_factory=lambda: mavlink2.MAVLink(None))
    sent: int = 0
    dropped: int = 0

    def send(self, message: Any) -> None:
        transport = self.writer.transport
        if transport.is_closing():
            return
        if transport.get_write_buffer_size() > MAX_CLIENT_BACKLOG:
            self.dropped += 1
            return
        self.writer.write(message.pack(self.encoder))
        self.sent += 1


class MavlinkSource:
    """A TCP server that streams the mix to every client and answers like a vehicle."""

    def __init__(self) -> None:
        self.clients: list[Client] = []
        self.boot = time.time()
        self.port = 0

    async def serve(self, ready: asyncio.Event) -> None:
        server = await asyncio.start_server(self._client, "127.0.0.1", 0)
        self.port = server.sockets[0].getsockname()[1]
        ready.set()
        async with server:
            next_due = {
                kind: time.monotonic() + i / len(STREAM_HZ) for i, kind in enumerate(STREAM_HZ)
            }
            while True:
                now = time.monotonic()
                for kind, hz in STREAM_HZ.items():
                    while next_due[kind] <= now:
                        message = build(kind, time.time(), self.boot)
                        for client in list(self.clients):
                            client.send(message)
                        next_due[kind] += 1 / hz
                await asyncio.sleep(TICK_S)

    async def _client(self, reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
        client = Client(writer)
        self.clients.append(client)
        try:
            while data := await reader.read(4096):
                for message in client.parser.parse_buffer(data) or []:
                    for reply in self._answer(message):
                        client.send(reply)
        except (ConnectionError, OSError):
            pass
        finally:
            self.clients.remove(client)
            writer.close()

    def _answer(self, message: Any) -> list[Any]:
        m = mavlink2
        kind = message.get_type()
        sender = message.get_srcSystem(), message.get_srcComponent()
        if kind == "COMMAND_LONG":
            return [
                m.MAVLink_command_ack_message(message.command, m.MAV_RESULT_ACCEPTED, 0, 0, *sender)
            ]
        if kind == "PARAM_REQUEST_LIST":
            return [self._param(name) for name in PARAMS]
        if kind == "PARAM_REQUEST_READ":
            names = list(PARAMS)
            index = message.param_index
            name = names[index] if 0 <= index < len(names) else message.param_id
            return [self._param(name)] if name in PARAMS else []
        if kind == "MISSION_REQUEST_LIST":
            return [m.MAVLink_mission_count_message(*sender, 0, message.mission_type)]
        return []

    def _param(self, name: str) -> Any:
        names = list(PARAMS)
        return mavlink2.MAVLink_param_value_message(
            name.encode(),
            PARAMS[name],
            mavlink2.MAV_PARAM_TYPE_REAL32,
            len(names),
            names.index(name),
        )


class UdpSink:
    """A GCS that only listens: counts, on a thread of its own, the frames sent to it."""

    def __init__(self) -> None:
        self.socket = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.socket.bind(("127.0.0.1", 0))
        self.socket.settimeout(0.5)
        self.port = self.socket.getsockname()[1]
        self.frames = 0
        threading.Thread(target=self._count, daemon=True).start()

    def _count(self) -> None:
        parser = mavlink2.MAVLink(None)
        while True:
            try:
                data = self.socket.recv(65535)
            except TimeoutError:
                continue
            except OSError:
                return  # closed
            self.frames += len(parser.parse_buffer(data) or [])


def run_source(ready: Callable[[MavlinkSource], None]) -> None:
    """The source on its own event loop, in a daemon thread of the benchmark process."""

    async def main() -> None:
        source = MavlinkSource()
        started = asyncio.Event()
        task = asyncio.create_task(source.serve(started))
        await started.wait()
        ready(source)
        await task

    asyncio.run(main())


# -- processes and /proc -------------------------------------------------------------


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


# -- the run ---------------------------------------------------------------------------


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


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--seconds", type=float, default=30.0, help="measured time (30)")
    parser.add_argument("--warmup", type=float, default=8.0, help="seconds before sampling (8)")
    parser.add_argument("--mavproxy", help="path to mavproxy.py (default: found beside python)")
    args = parser.parse_args()

    sources: list[MavlinkSource] = []
    source_up = threading.Event()

    def on_ready(source: MavlinkSource) -> None:
        sources.append(source)
        source_up.set()

    threading.Thread(target=run_source, args=(on_ready,), daemon=True).start()
    if not source_up.wait(10):
        print("the MAVLink source did not start", file=sys.stderr)
        return 1
    source = sources[0]
    fcu = f"tcp:127.0.0.1:{source.port}"

    workdir = Path(tempfile.mkdtemp(prefix="bench_agent_"))
    hub_port = free_port()
    hub_url = f"http://127.0.0.1:{hub_port}"
    password = "bench-admin-password"
    tokens = {VEHICLE_ID: "gcs_v_" + "a" * 40, FORWARDING_VEHICLE_ID: "gcs_v_" + "b" * 40}
    gcs = [sys.executable, "-m", "gcs"]  # the agents log as they do in service (INFO)
    hub = spawn(
        [
            *gcs,
            "--log-level",
            "WARNING",
            "hub",
            "--port",
            str(hub_port),
            "--data-dir",
            str(workdir / "hub"),
        ],
        workdir / "hub.log",
        {
            "GCS_ENVIRONMENT": "development",
            "GCS_ADMIN_PASSWORD": password,
            "GCS_AGENT_TOKENS": ",".join(f"{v}={t}" for v, t in tokens.items()),
        },
    )
    measured: list[Measured] = []
    with running(measured, [hub]):
        wait_for_hub(hub_url, hub)
        agent = [*gcs, "agent", "--fcu", fcu, "--hub", f"ws://127.0.0.1:{hub_port}"]
        for name, vehicle_id, sink in (
            ("agent", VEHICLE_ID, None),
            ("agent + forwarding to a GCS", FORWARDING_VEHICLE_ID, UdpSink()),
        ):
            forward = [] if sink is None else ["--mavlink-forward", f"udpout:127.0.0.1:{sink.port}"]
            log_path = workdir / f"{vehicle_id}.log"
            process = spawn(
                [*agent, "--vehicle-id", vehicle_id, *forward],
                log_path,
                {"GCS_AGENT_TOKEN": tokens[vehicle_id]},
            )
            measured.append(Measured(name, process, log_path, sink))
        sink, log_path = UdpSink(), workdir / "mavproxy.log"
        mavproxy = Measured("MAVProxy --out to a GCS", None, log_path, sink)
        mavproxy_path, mavproxy.problem = find_mavproxy(args.mavproxy)
        if mavproxy_path is not None:
            out = f"udpout:127.0.0.1:{sink.port}"
            mavproxy.process = spawn(
                [mavproxy_path, "--master", fcu, "--out", out, "--daemon", "--no-state"],
                log_path,
            )
        measured.append(mavproxy)

        # Warm-up: imports, connecting, the hub handshake, MAVProxy's parameter fetch.
        time.sleep(args.warmup)
        sent_before = [client.sent for client in source.clients]
        elapsed = sample([m for m in measured if m.process is not None], args.seconds)
        rates = [(c.sent - b) / elapsed for c, b in zip(source.clients, sent_before, strict=False)]
        try:
            vehicles = hub_vehicles(hub_url, password)
        except (urllib.error.URLError, OSError, KeyError) as error:
            vehicles = {}
            print(f"could not read the hub's vehicles: {error}")

    print_report(measured, rates, elapsed, vehicles, workdir)
    return 0


def print_report(
    measured: list[Measured],
    rates: list[float],
    elapsed: float,
    vehicles: dict[str, dict[str, Any]],
    workdir: Path,
) -> None:
    print(
        f"\nAgent footprint at {RATE:g} MAVLink messages/s in: {elapsed:.0f} s measured, "
        f"sampled each second from /proc ({os.cpu_count()} cores)"
    )
    print(
        f"{'process':<30} {'RSS MB median':>13} {'RSS MB max':>10} {'CPU % mean':>10} "
        f"{'CPU % max (1 s)':>15} {'to GCS msg/s':>12}"
    )
    for m in measured:
        if m.problem is not None or not m.rss_mb:
            print(f"{m.name:<30} not measured: {m.problem or 'no samples'}")
            continue
        forwarded = f"{m.forwarded / elapsed:.1f}" if m.sink is not None else "-"
        print(
            f"{m.name:<30} {statistics.median(m.rss_mb):>13.1f} {max(m.rss_mb):>10.1f} "
            f"{m.cpu_mean:>10.2f} {max(m.cpu_pct):>15.2f} {forwarded:>12}"
        )
    print(f"bar for the agent: <= {AGENT_BAR[0]:g} MB RSS, <= {AGENT_BAR[1]:g} % of one core")
    print("source: " + ", ".join(f"{rate:.1f}" for rate in rates) + " msg/s sent to each client")
    for vehicle_id in (VEHICLE_ID, FORWARDING_VEHICLE_ID):
        vehicle = vehicles.get(vehicle_id, {})
        age = time.time() - vehicle["last_seen"] if vehicle.get("last_seen") else None
        print(
            f"hub: {vehicle_id} connected={vehicle.get('connected')} "
            + (f"last telemetry {age:.1f} s ago" if age is not None else "no telemetry")
        )
    if importlib.util.find_spec("numpy") is not None:
        print(
            "note: numpy is importable by the agents' Python, so pymavlink.mavutil loaded it "
            "into them (about 13 MB of RSS an onboard install does not have); run the agents "
            "from a venv without MAVProxy's dependencies"
        )
    print(f"logs: {workdir}")


if __name__ == "__main__":
    sys.exit(main())
