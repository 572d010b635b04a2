"""Soak: a simulated fleet flies missions in a loop for a long time; at the end, memory
growth per process, latency drift and loss. Not part of the test suite.

    .venv/bin/python bench/soak.py                       # 20 vehicles, one hour
    .venv/bin/python bench/soak.py --duration 600 --json soak.json
    # options: --vehicles 20, --speedup 5, --sample-s 10

What runs, all on loopback and as `gcs demo` starts them: a real hub (SQLite), and per
vehicle a simulator and an agent. Each vehicle flies the same small mission (take-off to
15 m, 60 m out, back, RTL, which lands and disarms) again and again until the time is up,
its pack drain switched off so that the loop can go on for hours.

Measured:
- memory: every process's resident set (VmRSS) every ``--sample-s`` seconds; printed
  as start, end, end - start and the least-squares slope in MB per hour (what a leak
  looks like; the start is taken after a minute's warm-up, when caches have filled);
- latency: agent -> hub -> dashboard, for every live vehicle update a dashboard client
  (a WebSocket, as the browser's) receives: its arrival time minus the sample's time
  (``last_seen``, stamped by the agent; one machine, one clock). Printed as the median of
  the first and the last 10 % of the run and the p99 of each, and of the whole run;
- loss: after the agents have stopped (before the hub, so what they sent is stored), per
  agent run (stream) in the hub's store: samples sent (the highest sequence number + 1:
  the agent numbers from 0 without holes), stored (distinct numbers), missing and
  duplicates (rows - distinct; the store should make this impossible).

Prints Markdown tables, and with --json writes the same figures; asserts nothing.
"""

from __future__ import annotations

import argparse
import json
import os
import sqlite3
import statistics
import sys
import tempfile
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

import httpx
from pymavlink.dialects.v20 import ardupilotmega as mavlink2
from websockets.sync.client import connect

from gcs.launcher import FleetPlan, LocalFleet, free_port
from protocol.messages import CLIENT_WS_PATH

WARM_UP_S = 60.0
NORTH_DEG_PER_M = 1 / 111_320


@dataclass
class Samples:
    """Everything measured, appended to from several threads (list appends are atomic)."""

    rss_kb: dict[str, list[tuple[float, int]]] = field(default_factory=dict)
    latency: list[tuple[float, float]] = field(default_factory=list)  # (arrival, seconds)
    missions_flown: dict[str, int] = field(default_factory=dict)
    mission_errors: list[str] = field(default_factory=list)


def _rss_kb(pid: int) -> int | None:
    try:
        for line in Path(f"/proc/{pid}/status").read_text().splitlines():
            if line.startswith("VmRSS:"):
                return int(line.split()[1])
    except OSError:
        return None  # the process is gone
    return None


def sample_memory(
    fleet: LocalFleet, samples: Samples, every_s: float, stop: threading.Event
) -> None:
    while not stop.is_set():
        now = time.monotonic()
        for managed in list(fleet.processes):
            if (kb := _rss_kb(managed.process.pid)) is not None:
                samples.rss_kb.setdefault(managed.name, []).append((now, kb))
        stop.wait(every_s)


class Dashboard:
    """A dashboard's live feed: keeps each vehicle's newest state and times each update."""

    def __init__(self, base: str, token: str, samples: Samples) -> None:
        self.vehicles: dict[str, dict[str, Any]] = {}
        self._url = base.replace("http://", "ws://") + CLIENT_WS_PATH
        self._headers = {"Authorization": f"Bearer {token}"}
        self._samples = samples

    def run(self, stop: threading.Event) -> None:
        with connect(self._url, additional_headers=self._headers, max_queue=None) as socket:
            while not stop.is_set():
                try:
                    frame = socket.recv(timeout=1)
                except TimeoutError:
                    continue
                arrived = time.time()
                message = json.loads(frame)
                if message["type"] == "fleet":
                    self.vehicles = {v["id"]: v for v in message["vehicles"]}
                elif message["type"] == "vehicles":
                    # a batch of the vehicles that changed, each with what changed
                    for vehicle in message["vehicles"]:
                        merged = {**self.vehicles.get(vehicle["id"], {}), **vehicle}
                        self.vehicles[vehicle["id"]] = merged
                        if vehicle.get("state") is not None and vehicle.get("last_seen"):
                            self._samples.latency.append(
                                (time.monotonic(), arrived - vehicle["last_seen"])
                            )

    def state(self, vehicle_id: str) -> dict[str, Any]:
        return (self.vehicles.get(vehicle_id) or {}).get("state") or {}


def _mission(lat: float, lon: float) -> list[dict[str, Any]]:
    return [
        # where it stands: PX4 flies to a take-off's position, ArduPilot climbs in place
        {"command": mavlink2.MAV_CMD_NAV_TAKEOFF, "lat": lat, "lon": lon, "alt": 15},
        {
            "command": mavlink2.MAV_CMD_NAV_WAYPOINT,
            "lat": lat + 60 * NORTH_DEG_PER_M,
            "lon": lon,
            "alt": 15,
        },
        {"command": mavlink2.MAV_CMD_NAV_WAYPOINT, "lat": lat, "lon": lon, "alt": 15},
        {"command": mavlink2.MAV_CMD_NAV_RETURN_TO_LAUNCH},
    ]


def _wait(condition: Any, timeout_s: float, stop: threading.Event) -> bool:
    deadline = time.monotonic() + timeout_s
    while not condition():
        if stop.is_set() or time.monotonic() > deadline:
            return False
        stop.wait(0.5)  # polling the dashboard's copy of the state
    return True


def fly_missions(
    vehicle: str, api: httpx.Client, dashboard: Dashboard, samples: Samples, stop: threading.Event
) -> None:
    """Mission after mission until ``stop``; a failed one is noted and the loop goes on."""
    commands = f"/api/v1/vehicles/{vehicle}/commands"

    def ready() -> bool:
        state = dashboard.state(vehicle)
        return bool(
            state.get("gps_fix", 0) >= 3
            and state.get("home_lat") is not None
            and state.get("armed") is False
            and state.get("landed_state") == "on_ground"
        )

    while not stop.is_set():
        if not _wait(ready, 300, stop):
            if not stop.is_set():
                samples.mission_errors.append(f"{vehicle}: not back on the ground in 300 s")
            continue
        try:
            state = dashboard.state(vehicle)
            upload = api.post(
                f"/api/v1/vehicles/{vehicle}/mission",
                json={"items": _mission(state["home_lat"], state["home_lon"])},
            )
            upload.raise_for_status()
            for command in (
                {"name": "set_mode", "mode": "GUIDED"},
                {"name": "arm"},
                {"name": "set_mode", "mode": "AUTO"},
            ):
                answer = api.post(commands, json=command)
                answer.raise_for_status()
                outcome = answer.json()["outcome"]
                if outcome["status"] != "accepted":
                    raise RuntimeError(f"{command}: {outcome}")
        except (httpx.HTTPError, RuntimeError) as error:
            samples.mission_errors.append(f"{vehicle}: {error}"[:300])
            stop.wait(5)
            continue
        # Airborne, then back on the ground: one mission flown.
        if _wait(lambda: dashboard.state(vehicle).get("armed") is True, 60, stop) and _wait(
            lambda: dashboard.state(vehicle).get("armed") is False, 600, stop
        ):
            samples.missions_flown[vehicle] = samples.missions_flown.get(vehicle, 0) + 1


def stored_streams(data_dir: Path) -> list[dict[str, Any]]:
    with sqlite3.connect(data_dir / "gcs.sqlite3", timeout=30) as db:
        rows = db.execute(
            "SELECT vehicle_id, stream_id, count(*), count(DISTINCT seq), max(seq)"
            " FROM telemetry GROUP BY vehicle_id, stream_id ORDER BY vehicle_id"
        ).fetchall()
    return [
        {
            "vehicle": vehicle,
            "stream": stream,
            "sent": top + 1,
            "stored": distinct,
            "missing": top + 1 - distinct,
            "duplicates": rows_ - distinct,
        }
        for vehicle, stream, rows_, distinct, top in rows
    ]


def _percentile(values: list[float], q: float) -> float:
    ordered = sorted(values)
    return ordered[min(len(ordered) - 1, int(q * len(ordered)))] if ordered else float("nan")


def summarise(samples: Samples, started: float, streams: list[dict[str, Any]]) -> dict[str, Any]:
    memory = {}
    for name, series in sorted(samples.rss_kb.items()):
        warm = [(t, kb) for t, kb in series if t - started >= WARM_UP_S] or series
        if len(warm) < 2:
            continue
        hours = [(t - started) / 3600 for t, _ in warm]
        megabytes = [kb / 1024 for _, kb in warm]
        slope = statistics.linear_regression(hours, megabytes).slope
        memory[name] = {
            "start_mb": round(megabytes[0], 1),
            "end_mb": round(megabytes[-1], 1),
            "growth_mb": round(megabytes[-1] - megabytes[0], 1),
            "slope_mb_per_h": round(slope, 2),
        }
    latencies = samples.latency
    tenth = max(1, len(latencies) // 10)
    first = [seconds * 1000 for _, seconds in latencies[:tenth]]
    last = [seconds * 1000 for _, seconds in latencies[-tenth:]]
    every = [seconds * 1000 for _, seconds in latencies]
    latency = {
        "updates": len(latencies),
        "first_10pct_median_ms": round(statistics.median(first), 1) if first else None,
        "last_10pct_median_ms": round(statistics.median(last), 1) if last else None,
        "first_10pct_p99_ms": round(_percentile(first, 0.99), 1),
        "last_10pct_p99_ms": round(_percentile(last, 0.99), 1),
        "p99_ms": round(_percentile(every, 0.99), 1),
    }
    loss = {
        "sent": sum(s["sent"] for s in streams),
        "stored": sum(s["stored"] for s in streams),
        "missing": sum(s["missing"] for s in streams),
        "duplicates": sum(s["duplicates"] for s in streams),
        "streams": streams,
    }
    return {
        "memory": memory,
        "latency": latency,
        "loss": loss,
        "missions_flown": sum(samples.missions_flown.values()),
        "mission_errors": samples.mission_errors[:20],
        "mission_error_count": len(samples.mission_errors),
    }


def print_report(report: dict[str, Any], args: argparse.Namespace) -> None:
    print(f"\nSoak: {args.vehicles} vehicles, {args.duration:g} s, speed-up {args.speedup:g}")
    print(f"load average (1 min) at the end: {os.getloadavg()[0]:.2f} on {os.cpu_count()} cores")
    print(f"missions flown: {report['missions_flown']}, failed: {report['mission_error_count']}")
    print("\n| process | RSS start (MB) | end (MB) | growth (MB) | slope (MB/h) |")
    print("|---|---:|---:|---:|---:|")
    for name, figures in report["memory"].items():
        print(
            f"| {name} | {figures['start_mb']} | {figures['end_mb']} | "
            f"{figures['growth_mb']} | {figures['slope_mb_per_h']} |"
        )
    latency = report["latency"]
    print("\n| latency agent->hub->dashboard | median (ms) | p99 (ms) |")
    print("|---|---:|---:|")
    print(f"| first 10 % | {latency['first_10pct_median_ms']} | {latency['first_10pct_p99_ms']} |")
    print(f"| last 10 % | {latency['last_10pct_median_ms']} | {latency['last_10pct_p99_ms']} |")
    print(f"| whole run ({latency['updates']} updates) | | {latency['p99_ms']} |")
    loss = report["loss"]
    print(
        f"\nloss: {loss['sent']} samples sent, {loss['stored']} stored, "
        f"{loss['missing']} missing, {loss['duplicates']} duplicates"
    )
    for error in report["mission_errors"]:
        print(f"  mission error: {error}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--duration", type=float, default=3600.0, help="seconds of flying")
    parser.add_argument("--vehicles", type=int, default=20)
    parser.add_argument("--speedup", type=float, default=5.0)
    parser.add_argument("--sample-s", type=float, default=10.0, help="memory sampling period")
    parser.add_argument("--json", type=Path, help="also write the figures here")
    parser.add_argument("--keep", type=Path, help="use this data folder (kept) instead")
    args = parser.parse_args()

    data_dir = args.keep or Path(tempfile.mkdtemp(prefix="gcs-soak-"))
    # The benchmark's missions are the admin's requests: not the per-user limit's subject.
    os.environ["GCS_COMMANDS_PER_SECOND"] = "1000"
    plan = FleetPlan(
        vehicles=args.vehicles, port=free_port(), data_dir=data_dir, speedup=args.speedup
    )
    samples = Samples()
    stop = threading.Event()
    with LocalFleet(plan) as fleet:
        fleet.start()
        fleet.wait_until_ready(120)
        started = time.monotonic()
        threading.Thread(
            target=sample_memory, args=(fleet, samples, args.sample_s, stop), daemon=True
        ).start()
        login = httpx.post(
            f"{plan.hub_http}/api/v1/auth/token",
            data={"username": "admin", "password": plan.admin_password},
        )
        login.raise_for_status()
        token = login.json()["access_token"]
        dashboard = Dashboard(plan.hub_http, token, samples)
        threading.Thread(target=dashboard.run, args=(stop,), daemon=True).start()
        headers = {"Authorization": f"Bearer {token}"}
        with httpx.Client(base_url=plan.hub_http, headers=headers, timeout=60) as api:
            for index in range(args.vehicles):
                vehicle = plan.vehicle_id(index)
                drain = f"/api/v1/vehicles/{vehicle}/params/SIM_BATT_DRAIN"
                deadline = time.monotonic() + 120
                while api.put(drain, json={"value": 0.0}).status_code != 200:
                    if time.monotonic() > deadline:
                        raise SystemExit(f"{vehicle} never took SIM_BATT_DRAIN")
                    time.sleep(1)  # the agent is still connecting
            pilots = [
                threading.Thread(
                    target=fly_missions,
                    args=(plan.vehicle_id(i), api, dashboard, samples, stop),
                    daemon=True,
                )
                for i in range(args.vehicles)
            ]
            for pilot in pilots:
                pilot.start()
            stop.wait(max(0.0, args.duration - (time.monotonic() - started)))
            stop.set()
            for pilot in pilots:
                pilot.join(30)
        fleet.stop(30)  # agents first: what they sent is stored before the hub stops
    report = summarise(samples, started, stored_streams(data_dir))
    report["config"] = {
        "vehicles": args.vehicles,
        "duration_s": args.duration,
        "speedup": args.speedup,
        "cores": os.cpu_count(),
        "data_dir": str(data_dir),
    }
    print_report(report, args)
    if args.json:
        args.json.write_text(json.dumps(report, indent=2))


if __name__ == "__main__":
    main()
