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
import importlib.util
import os
import statistics
import sys
import tempfile
import threading
import time
import urllib.error
import urllib.request
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))


from bench.agent_footprint.mavlink_source import RATE, MavlinkSource, UdpSink, run_source
from bench.agent_footprint.processes import (
    Measured,
    find_mavproxy,
    hub_vehicles,
    running,
    sample,
    spawn,
    wait_for_hub,
)
from gcs.launcher import free_port

VEHICLE_ID = "bench_agent"
FORWARDING_VEHICLE_ID = "bench_forwarding"
AGENT_BAR = (60.0, 5.0)  # MB RSS, % of one core


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
