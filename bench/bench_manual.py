"""Manual control: the delay from a browser's stick frame to MANUAL_CONTROL at the flight
controller, and the rate that arrives there, with 1 and with 20 vehicles flying
(DESIGN.md: p99 <= 30 ms at >= 25 Hz on loopback).

    .venv/bin/python bench/bench_manual.py            # both runs, 15 s of input each
    # options: --vehicles 1 20, --seconds 15, --rate-hz 25

What runs, all on loopback: a real hub, and per vehicle a real simulator (ArduCopter's
MAVLink, real time) and a real agent, as `gcs demo` starts them. Between each agent and its
simulator the benchmark puts a TCP tap that passes every byte on and notes the moment each
MANUAL_CONTROL from the agent goes by: that is "at the flight controller" (one extra
loopback hop, so the figure errs high). Every vehicle takes off to 10 m and hovers; then
one client per vehicle takes its lease over the dashboard's WebSocket and sends `manual`
frames at 25 Hz, as the dashboard's pilot view does (a frame slot missed is skipped, never
sent twice). Each frame's send time and its MANUAL_CONTROL's arrival are on the same
monotonic clock (CLOCK_MONOTONIC is one clock for every process on the machine); frames
are matched by values unique to each (roll and yaw a few percent, the sequence encoded).

The "browser" here is a Python WebSocket client, not Chromium: the figure is the
hub-and-agent path from the socket to the flight controller. The page's own part (a
setInterval tick reading the stick) is the same whatever the fleet does.

Prints a table (with the machine's 1-minute load average when the pilots started: the
figures are only as good as the cores the fleet got); asserts nothing.
"""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import json
import multiprocessing
import os
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
import websockets
from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from gcs.launcher import FleetPlan, LocalFleet, free_port
from protocol.messages import CLIENT_WS_PATH

BAR_P99_MS = 30.0
BAR_RATE_HZ = 25.0
KEY_SPAN = 200  # roll and yaw carry seq % 200 and seq // 200 % 200, minus 100


def frame_key(seq: int) -> tuple[int, int]:
    return (seq % KEY_SPAN) - KEY_SPAN // 2, (seq // KEY_SPAN) % KEY_SPAN - KEY_SPAN // 2


# -- the tap between agent and simulator ------------------------------------------------


@dataclass
class Tap:
    """Per vehicle: when each MANUAL_CONTROL (by its key) passed on its way to the FCU."""

    arrivals: dict[tuple[int, int], float] = field(default_factory=dict)
    count: int = 0
    first: float | None = None
    last: float | None = None


class Taps:
    """TCP pass-throughs on an event loop of their own, in a daemon thread."""

    def __init__(self) -> None:
        self.loop = asyncio.new_event_loop()
        threading.Thread(target=self.loop.run_forever, daemon=True).start()
        self.taps: dict[str, Tap] = {}

    def add(self, vehicle_id: str, sim_port: int) -> int:
        tap = self.taps[vehicle_id] = Tap()
        ready: asyncio.Future[int] = asyncio.run_coroutine_threadsafe(
            self._listen(tap, sim_port), self.loop
        )  # type: ignore[assignment]
        return ready.result(10)

    async def _listen(self, tap: Tap, sim_port: int) -> int:
        async def handle(reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
            try:
                sim_reader, sim_writer = await asyncio.open_connection("127.0.0.1", sim_port)
            except OSError:  # the simulator not listening yet: the agent retries
                writer.close()
                return
            parser = mavlink2.MAVLink(None)
            parser.robust_parsing = True

            async def upstream() -> None:  # agent -> FCU: watched
                while data := await reader.read(65536):
                    now = time.monotonic()
                    sim_writer.write(data)
                    for message in parser.parse_buffer(data) or []:
                        if message.get_type() == "MANUAL_CONTROL":
                            tap.arrivals[(message.y, message.r)] = now
                            tap.count += 1
                            tap.first = tap.first or now
                            tap.last = now

            async def downstream() -> None:
                while data := await sim_reader.read(65536):
                    writer.write(data)

            with contextlib.suppress(ConnectionError, OSError):
                await asyncio.gather(upstream(), downstream())
            writer.close()
            sim_writer.close()

        server = await asyncio.start_server(handle, "127.0.0.1", 0)
        self.servers = [*getattr(self, "servers", []), server]
        return int(server.sockets[0].getsockname()[1])


class TappedFleet(LocalFleet):
    """The demo fleet, each agent reaching its simulator through a tap."""

    def __init__(self, plan: FleetPlan, taps: Taps) -> None:
        super().__init__(plan)
        self.taps = taps

    def start_agent(self, index: int, sim_port: int) -> None:
        super().start_agent(index, self.taps.add(self.vehicle_id(index), sim_port))


# -- the REST calls of the set-up -------------------------------------------------------


def wait_for(condition: Any, timeout_s: float, what: str) -> None:
    deadline = time.monotonic() + timeout_s
    while not condition():
        if time.monotonic() > deadline:
            raise TimeoutError(f"{what} after {timeout_s:.0f} s")
        time.sleep(0.5)  # set-up only: the measured part waits on nothing


def hovering(api: httpx.Client, vehicles: list[str]) -> None:
    def states() -> dict[str, Any]:
        listed = api.get("/api/v1/vehicles").json()
        items = listed["vehicles"] if isinstance(listed, dict) else listed
        return {v["id"]: v.get("state") or {} for v in items}

    wait_for(
        lambda: all(states().get(v, {}).get("ready_to_fly") for v in vehicles), 120, "not ready"
    )

    def polite(method: str, url: str, body: dict[str, Any]) -> None:
        """One request, waiting out the hub's command rate limit (429)."""
        while (answer := api.request(method, url, json=body)).status_code == 429:
            time.sleep(float(answer.headers.get("retry-after", "1")))
        answer.raise_for_status()

    for vehicle in vehicles:
        path = f"/api/v1/vehicles/{vehicle}"
        polite("PUT", f"{path}/params/SYSID_MYGCS", {"value": 254})
        polite("POST", f"{path}/commands", {"name": "takeoff", "altitude": 10.0})
    wait_for(
        lambda: all((states()[v].get("alt_rel") or 0) > 9 for v in vehicles), 120, "not at 10 m"
    )


# -- the pilots -------------------------------------------------------------------------


@dataclass
class Stream:
    vehicle_id: str
    sent: dict[tuple[int, int], float] = field(default_factory=dict)
    refused: list[str] = field(default_factory=list)
    ended: str | None = None


async def fly(base: str, token: str, stream: Stream, seconds: float, rate_hz: float) -> None:
    url = base.replace("http://", "ws://") + CLIENT_WS_PATH
    async with websockets.connect(
        url, additional_headers={"Authorization": f"Bearer {token}"}
    ) as ws:
        granted = asyncio.Event()

        async def read() -> None:
            async for frame in ws:
                # Every pilot's feed also carries the whole fleet's updates, as a
                # dashboard's does: only the lease's messages are parsed here.
                head = frame[:20] if isinstance(frame, str) else ""
                if '"lease"' not in head and '"error"' not in head:
                    continue
                message = json.loads(frame)
                if message.get("vehicle_id") not in (None, stream.vehicle_id):
                    continue
                if message["type"] == "lease" and message["holder"] == "admin":
                    granted.set()
                elif message["type"] == "lease" and granted.is_set():
                    stream.ended = message["reason"]
                elif message["type"] == "error":
                    stream.refused.append(message["message"])

        reader = asyncio.create_task(read())
        await ws.send(
            json.dumps({"type": "control", "vehicle_id": stream.vehicle_id, "action": "acquire"})
        )
        await asyncio.wait_for(granted.wait(), 60)
        period = 1.0 / rate_hz
        seq = 0
        start = next_at = time.monotonic()
        while (now := time.monotonic()) < start + seconds:
            seq += 1
            roll, yaw = frame_key(seq)
            frame = {
                "type": "manual",
                "vehicle_id": stream.vehicle_id,
                "seq": seq,
                "axes": {"x": 150, "y": roll, "z": 500, "r": yaw},
                "source": "touch",
            }
            stream.sent[(roll, yaw)] = time.monotonic()
            await ws.send(json.dumps(frame))
            next_at += period
            if next_at < now - period:  # slots missed: skip them, never a burst
                next_at = now + period
            await asyncio.sleep(max(0.0, next_at - time.monotonic()))
        await ws.send(
            json.dumps({"type": "control", "vehicle_id": stream.vehicle_id, "action": "release"})
        )
        await asyncio.sleep(0.5)
        reader.cancel()


async def fly_all(
    base: str, token: str, vehicles: list[str], seconds: float, rate_hz: float
) -> list[Stream]:
    streams = [Stream(v) for v in vehicles]
    await asyncio.gather(*(fly(base, token, s, seconds, rate_hz) for s in streams))
    return streams


def fly_process(
    base: str, token: str, vehicles: list[str], seconds: float, rate_hz: float
) -> list[Stream]:
    return asyncio.run(fly_all(base, token, vehicles, seconds, rate_hz))


def cpu_seconds(pid: int) -> float:
    """User and system CPU time of one process, from /proc."""
    try:
        fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    except OSError:
        return 0.0
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def percentile(values: list[float], q: float) -> float:
    ordered = sorted(values)
    return ordered[min(len(ordered) - 1, max(0, round(q / 100 * (len(ordered) - 1))))]


def run(count: int, seconds: float, rate_hz: float) -> dict[str, Any]:
    taps = Taps()
    with tempfile.TemporaryDirectory(prefix="bench-manual-") as folder:
        plan = FleetPlan(vehicles=count, port=free_port(), data_dir=Path(folder), speedup=1.0)
        with TappedFleet(plan, taps) as fleet:
            fleet.start()
            ready_by = time.monotonic() + 120
            while True:
                try:  # a loaded machine can take longer than the health check's 2 s
                    fleet.wait_until_ready(120)
                    break
                except TimeoutError:
                    if time.monotonic() > ready_by:
                        raise
            base = plan.hub_http
            login = {"username": "admin", "password": plan.admin_password}
            answer = httpx.post(f"{base}/api/v1/auth/token", data=login, timeout=60)
            token = answer.raise_for_status().json()["access_token"]
            vehicles = [plan.vehicle_id(i) for i in range(count)]
            headers = {"Authorization": f"Bearer {token}"}
            with httpx.Client(base_url=base, headers=headers, timeout=60) as api:
                hovering(api, vehicles)
            load = os.getloadavg()[0]
            cpu_before = {m.name: cpu_seconds(m.process.pid) for m in fleet.processes}
            wall_before = time.monotonic()
            # The pilots in a process of their own, so the taps' thread (which passes
            # every simulator's telemetry on) never holds their interpreter lock.
            # Up to 5 pilots per process, as 20 dashboards would not share one thread.
            context = multiprocessing.get_context("fork")
            groups = [vehicles[i : i + 5] for i in range(0, len(vehicles), 5)]
            with context.Pool(len(groups)) as pool:
                parts = pool.starmap(
                    fly_process, [(base, token, group, seconds, rate_hz) for group in groups]
                )
            streams = [stream for part in parts for stream in part]
            wall = time.monotonic() - wall_before
            used = {
                m.name: cpu_seconds(m.process.pid) - cpu_before.get(m.name, 0.0)
                for m in fleet.processes
            }
    delays, rates, lost, ended = [], [], 0, []
    for stream in streams:
        tap = taps.taps[stream.vehicle_id]
        for key, sent_at in stream.sent.items():
            arrived = tap.arrivals.get(key)
            if arrived is None:
                lost += 1
            else:
                delays.append((arrived - sent_at) * 1000)
        if tap.first is not None and tap.last is not None and tap.count > 1:
            rates.append((tap.count - 1) / (tap.last - tap.first))
        if stream.ended and "released" not in stream.ended:
            ended.append(f"{stream.vehicle_id}: {stream.ended}")
    return {
        "vehicles": count,
        "frames": sum(len(s.sent) for s in streams),
        "p50": statistics.median(delays),
        "p99": percentile(delays, 99),
        "max": max(delays),
        "rate_min": min(rates),
        "rate_mean": statistics.mean(rates),
        "lost": lost,
        "ended": ended,
        "load": load,
        # Share of one core while the pilots flew (their lease set-up included).
        "hub_cpu": 100 * used.get("hub", 0.0) / wall,
        "agent_cpu": 100
        * statistics.mean(v for k, v in used.items() if k.startswith("agent"))
        / wall,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--vehicles", type=int, nargs="+", default=[1, 20])
    parser.add_argument("--seconds", type=float, default=15.0)
    parser.add_argument("--rate-hz", type=float, default=25.0)
    args = parser.parse_args()
    results = [run(count, args.seconds, args.rate_hz) for count in args.vehicles]
    rate, seconds = f"{args.rate_hz:g} Hz", f"{args.seconds:g} s"
    print(f"\nbrowser input -> MANUAL_CONTROL at the FCU, {rate} per vehicle, {seconds}")
    heads = (
        "vehicles",
        "frames",
        "p50 ms",
        "p99 ms",
        "max ms",
        "rate min",
        "rate mean",
        "lost",
        "load",
    )
    print(" ".join(f"{h:>9}" for h in heads) + "  bar")
    for r in results:
        ok = r["p99"] <= BAR_P99_MS and r["rate_min"] >= BAR_RATE_HZ * 0.98 and r["lost"] == 0
        cells = (
            f"{r['vehicles']}",
            f"{r['frames']}",
            f"{r['p50']:.1f}",
            f"{r['p99']:.1f}",
            f"{r['max']:.1f}",
            f"{r['rate_min']:.1f} Hz",
            f"{r['rate_mean']:.1f} Hz",
            f"{r['lost']}",
            f"{r['load']:.1f}",
        )
        verdict = "met" if ok else "NOT met"
        print(" ".join(f"{c:>9}" for c in cells) + f"  {verdict} (p99 <= 30 ms at >= 25 Hz)")
        print(
            f"          CPU while flying: hub {r['hub_cpu']:.0f} % of a core, "
            f"each agent {r['agent_cpu']:.0f} %"
        )
        for line in r["ended"]:
            print(f"          lease ended early: {line}")


if __name__ == "__main__":
    main()
