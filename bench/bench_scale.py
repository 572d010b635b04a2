"""Scale: N simulated agents at R Hz and M dashboards on one hub (or several), measured.

    .venv/bin/python bench/bench_scale.py --vehicles 100 --rate 10 --dashboards 5
    # options: --duration 20, --database postgresql+psycopg://postgres@127.0.0.1:5432/x,
    #          --hub-url http://host:port (repeatable), --processes 2, --json out.json

What runs: unless ``--hub-url`` is given, a real hub process (`gcs hub`, no 3D view) on
loopback with a fresh data folder, on SQLite there or on ``--database``. The agents are
light simulated ones, not the agent package: each speaks the real agent protocol
(protocol.messages) over its own WebSocket with its own enrolment token (GCS_AGENT_TOKENS
for a hub started here, the admin API otherwise): hello, then one ``telemetry`` frame per
1/R s, numbered from 0, answering pings and keeping what the hub acks. They are spread
over ``--processes`` processes. The dashboards are WebSocket clients of the live feed in
one more process, logged in as the admin, subscribed to everything (the feed sends all).

Measured:
- throughput: telemetry frames sent per second, and stored per second (acks);
- loss and duplicates by sequence number: in the database (every frame sent stored once:
  a SQL count per vehicle after the run) and at the dashboards (a vehicle's states come
  in increasing order, none twice, and each ends at the last frame sent; the feed
  coalesces, so the intermediate states a dashboard skips are not a loss);
- agent -> dashboard delay: each frame carries its send time (time.time(), one clock for
  every process on the machine) as its ``time``, which the feed passes on as
  ``last_seen``; a dashboard takes its receive time minus that, per vehicle state;
- agent -> ack delay (stored in the database and told back), p50 and p99;
- the hub's CPU (% of one core) and peak RSS, from /proc (a hub started here, or
  ``--hub-pid``).

It prints one table and, with ``--json``, writes the figures for side-by-side runs. It
asserts nothing; tests/integration/test_bench_scale.py runs a small one to keep it working.
"""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import json
import math
import multiprocessing
import os
import secrets
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from array import array
from collections.abc import Iterator
from dataclasses import asdict, dataclass, field
from multiprocessing.synchronize import Event as EventType
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

import httpx
import orjson
import websockets
from sqlalchemy import create_engine, text

from gcs.launcher import free_port
from protocol.messages import AGENT_WS_PATH, CLIENT_WS_PATH, PROTOCOL_VERSION

ADMIN_PASSWORD = "bench-admin-password"
DRAIN_TIMEOUT_S = 180.0  # after the run, how long the agents wait for their last acks
REPO = Path(__file__).resolve().parent.parent


def vehicle_id(index: int) -> str:
    return f"bench_{index:05d}"


# -- the agents --------------------------------------------------------------------------


@dataclass
class AgentResult:
    sent: dict[str, int] = field(default_factory=dict)  # frames sent per vehicle
    acked: dict[str, int] = field(default_factory=dict)  # the highest seq acked
    ack_delays_ms: list[float] = field(default_factory=list)
    refused: list[str] = field(default_factory=list)
    last_ack_at: float = 0.0
    late_slots: int = 0  # send slots this process was too busy to keep


def telemetry_frame(seq: int, sent_at: float, index: int) -> bytes:
    """A realistic telemetry frame: what an agent sends about a multirotor in flight."""
    return orjson.dumps(
        {
            "type": "telemetry",
            "seq": seq,
            "time": sent_at,
            "state": {
                "mode": "GUIDED",
                "armed": True,
                "system_status": "ACTIVE",
                "landed_state": "in_air",
                "landed_state_source": "autopilot",
                "lat": 47.39 + index * 1e-4 + seq * 1e-7,
                "lon": 8.54 + seq * 1e-7,
                "alt_msl": 520.0 + seq % 50,
                "alt_rel": 30.0,
                "heading_deg": float(seq % 360),
                "groundspeed": 5.0,
                "climb_rate": 0.1,
                "vn": 3.0,
                "ve": 4.0,
                "roll_deg": 1.5,
                "pitch_deg": -2.0,
                "battery_voltage": 15.9,
                "battery_current": 12.5,
                "battery_remaining": 80.0,
                "gps_fix": 3,
                "satellites": 14,
                "ready_to_fly": True,
                "home_lat": 47.39,
                "home_lon": 8.54,
                "home_alt_msl": 490.0,
                # The sequence number, so that a dashboard can tell which frame it sees.
                "mission_current": seq,
                "mission_total": 10**9,
            },
        }
    )


async def run_agent(
    url: str,
    index: int,
    token: str,
    rate_hz: float,
    duration_s: float,
    welcomed: asyncio.Event,
    start: asyncio.Future[float],
    result: AgentResult,
    compression: str | None,
) -> None:
    vid = vehicle_id(index)
    stream = f"bench-{index}-{secrets.token_hex(4)}"
    hello = {
        "type": "hello",
        "protocol": PROTOCOL_VERSION,
        "vehicle_id": vid,
        "autopilot": "ardupilot",
        "vehicle_type": "multirotor",
        "system_id": 1 + index % 250,
        "modes": ["STABILIZE", "GUIDED", "AUTO", "LOITER", "RTL", "LAND"],
        "capabilities": [],
        "agent_version": "bench",
        "stream_id": stream,
    }
    sent_at: dict[int, float] = {}
    acked = -1
    seq = 0
    done = asyncio.Event()
    async with websockets.connect(
        url,
        additional_headers={"Authorization": f"Bearer {token}"},
        compression=compression,  # type: ignore[arg-type]
        max_queue=None,
        ping_interval=None,
        open_timeout=60,
    ) as websocket:
        await websocket.send(orjson.dumps(hello).decode())
        welcome = orjson.loads(await websocket.recv())
        welcomed.set()
        if welcome.get("type") != "welcome":
            result.refused.append(f"{vid}: {welcome}")
            return
        start_at = await start
        stop_at = start_at + duration_s

        async def receive() -> None:
            nonlocal acked
            async for frame in websocket:
                message = orjson.loads(frame)
                kind = message.get("type")
                if kind == "ack" and message.get("telemetry_seq") is not None:
                    now = time.time()
                    upto = message["telemetry_seq"]
                    for s in range(acked + 1, upto + 1):
                        if (at := sent_at.pop(s, None)) is not None:
                            result.ack_delays_ms.append((now - at) * 1000)
                    acked = max(acked, upto)
                    result.acked[vid] = acked
                    result.last_ack_at = now
                    if seq > 0 and acked >= seq - 1 and time.time() >= stop_at:
                        done.set()
                elif kind == "ping":
                    await websocket.send(
                        orjson.dumps({"type": "pong", "nonce": message["nonce"]}).decode()
                    )
                elif kind == "resend":
                    result.refused.append(f"{vid}: hub asked for a resend {message}")

        receiver = asyncio.create_task(receive())
        period = 1.0 / rate_hz
        # Spread the fleet over the period, as independent vehicles are.
        slot = start_at + period * ((index * 0.618) % 1.0)
        try:
            while slot < stop_at:
                delay = slot - time.time()
                if delay > 0:
                    await asyncio.sleep(delay)
                elif delay < -period:
                    result.late_slots += 1
                now = time.time()
                sent_at[seq] = now
                await websocket.send(telemetry_frame(seq, now, index).decode())
                seq += 1
                slot += period
            result.sent[vid] = seq
            if seq == 0 or acked >= seq - 1:
                done.set()
            with contextlib.suppress(TimeoutError):
                await asyncio.wait_for(done.wait(), DRAIN_TIMEOUT_S)
        finally:
            receiver.cancel()
            with contextlib.suppress(asyncio.CancelledError, Exception):
                await receiver


def agent_process(
    urls: list[str],
    indices: list[int],
    tokens: dict[int, str],
    rate_hz: float,
    duration_s: float,
    compression: str | None,
    connected: Any,
    go: EventType,
    start_box: Any,
    results: Any,
) -> None:
    async def main() -> None:
        result = AgentResult()
        start: asyncio.Future[float] = asyncio.get_running_loop().create_future()
        welcomed = {index: asyncio.Event() for index in indices}
        tasks = []
        for index in indices:
            url = urls[index % len(urls)].replace("http", "ws", 1) + AGENT_WS_PATH
            tasks.append(
                asyncio.create_task(
                    run_agent(
                        url,
                        index,
                        tokens[index],
                        rate_hz,
                        duration_s,
                        welcomed[index],
                        start,
                        result,
                        compression,
                    )
                )
            )
            await asyncio.sleep(0.002)  # connect as a fleet powers up, not all in one instant
        for event in welcomed.values():
            await event.wait()
        connected.put(len(indices))
        await asyncio.to_thread(go.wait)
        start.set_result(start_box.value)
        await asyncio.gather(*tasks)
        results.put(asdict(result))

    try:
        import uvloop

        uvloop.run(main())
    except ImportError:
        asyncio.run(main())


# -- the dashboards ----------------------------------------------------------------------


@dataclass
class DashboardResult:
    frames: int = 0
    updates: int = 0
    delays_ms: list[float] = field(default_factory=list)
    regressions: int = 0  # a state older than one already shown
    repeats: int = 0  # the same state twice
    last_seq: dict[str, int] = field(default_factory=dict)
    closed: list[str] = field(default_factory=list)
    bytes_in: int = 0


async def run_dashboard(
    url: str, token: str, result: DashboardResult, stop: asyncio.Event, connected: asyncio.Event
) -> None:
    delays = array("d")
    last = result.last_seq
    links: dict[str, bool | None] = {}
    async with websockets.connect(
        url,
        additional_headers={"Authorization": f"Bearer {token}"},
        max_queue=None,
        max_size=None,
        open_timeout=60,
    ) as websocket:
        connected.set()

        def vehicle(change: dict[str, Any], now: float) -> None:
            vid = change["id"]
            if not vid.startswith("bench_"):
                return
            state = change.get("state") or {}
            seq = state.get("mission_current")
            if seq is None:
                return
            result.updates += 1
            previous = last.get(vid, -1)
            connected = change.get("connected")
            if seq < previous:
                result.regressions += 1
            elif seq == previous:
                # The same state again is a duplicate, unless the link changed (an agent
                # that leaves keeps its last state, now offline).
                result.repeats += links.get(vid) == connected
                links[vid] = connected
            else:
                links[vid] = connected
                last[vid] = seq
                if change.get("last_seen") is not None:
                    delays.append((now - change["last_seen"]) * 1000)

        while not stop.is_set():
            try:
                frame = await asyncio.wait_for(websocket.recv(), 0.5)
            except TimeoutError:
                continue
            except websockets.ConnectionClosed as closed:
                result.closed.append(f"{closed.rcvd}")
                break
            now = time.time()
            result.frames += 1
            result.bytes_in += len(frame)
            message = orjson.loads(frame)
            kind = message.get("type")
            if kind == "vehicles":
                for change in message["vehicles"]:
                    vehicle(change, now)
            elif kind == "vehicle":  # a hub from before batching
                vehicle(message["vehicle"], now)
            elif kind == "fleet":
                for summary in message["vehicles"]:
                    state = summary.get("state") or {}
                    if summary["id"].startswith("bench_") and state.get("mission_current"):
                        last[summary["id"]] = max(
                            last.get(summary["id"], -1), state["mission_current"]
                        )
    result.delays_ms = delays.tolist()


def dashboard_process(
    urls: list[str], token: str, count: int, connected: Any, stop_flag: EventType, results: Any
) -> None:
    async def main() -> None:
        stop = asyncio.Event()
        outcomes = [DashboardResult() for _ in range(count)]
        ready = [asyncio.Event() for _ in range(count)]
        tasks = [
            asyncio.create_task(
                run_dashboard(
                    urls[i % len(urls)].replace("http", "ws", 1) + CLIENT_WS_PATH,
                    token,
                    outcomes[i],
                    stop,
                    ready[i],
                )
            )
            for i in range(count)
        ]
        for event in ready:
            await event.wait()
        connected.put(count)
        await asyncio.to_thread(stop_flag.wait)
        stop.set()
        await asyncio.gather(*tasks)
        results.put([asdict(outcome) for outcome in outcomes])

    try:
        import uvloop

        uvloop.run(main())
    except ImportError:
        asyncio.run(main())


# -- the hub -----------------------------------------------------------------------------


@contextlib.contextmanager
def started_hub(
    vehicles: int, database: str | None, tokens: dict[int, str], log_path: Path
) -> Iterator[tuple[str, int]]:
    data_dir = Path(tempfile.mkdtemp(prefix="bench-scale-"))
    port = free_port()
    env = {
        **os.environ,
        "GCS_ENVIRONMENT": "development",
        "GCS_ADMIN_PASSWORD": ADMIN_PASSWORD,
        "GCS_VIZ_ENABLED": "false",
        "GCS_AGENT_TOKENS": ",".join(f"{vehicle_id(i)}={t}" for i, t in tokens.items()),
        # Every agent and dashboard is a connection; the default 1,000 is a guard, not a
        # measure of what the hub holds.
        "GCS_MAX_CONNECTIONS": str(max(1000, 2 * vehicles + 100)),
        "GCS_COMMANDS_PER_SECOND": "1000",
    }
    if database:
        env["DATABASE_URL"] = database
    gcs = shutil.which("gcs", path=str(Path(sys.executable).parent)) or "gcs"
    with log_path.open("wb") as log:
        process = subprocess.Popen(
            [gcs, "hub", "--host", "127.0.0.1", "--port", str(port), "--data-dir", str(data_dir)],
            env=env,
            stdout=log,
            stderr=subprocess.STDOUT,
        )
    url = f"http://127.0.0.1:{port}"
    try:
        deadline = time.monotonic() + 120
        while True:
            with contextlib.suppress(httpx.HTTPError):
                if httpx.get(f"{url}/api/v1/health", timeout=2).status_code == 200:
                    break
            if process.poll() is not None or time.monotonic() > deadline:
                raise RuntimeError(f"the hub did not start: see {log_path}")
            time.sleep(0.2)
        yield url, process.pid
    finally:
        process.terminate()
        try:
            process.wait(30)
        except subprocess.TimeoutExpired:
            process.kill()
        shutil.rmtree(data_dir, ignore_errors=True)


def hub_data_dir(pid: int) -> Path:
    """The data folder of the hub started here (its SQLite file is there)."""
    args = Path(f"/proc/{pid}/cmdline").read_bytes().decode().split("\0")
    return Path(args[args.index("--data-dir") + 1])


def stored_counts(database_url: str) -> dict[str, tuple[int, int]]:
    """Per bench vehicle: rows stored, and distinct sequence numbers among them."""
    engine = create_engine(database_url)
    try:
        with engine.connect() as connection:
            rows = connection.execute(
                text(
                    "SELECT vehicle_id, count(*), count(DISTINCT seq) FROM telemetry "
                    "WHERE vehicle_id LIKE 'bench_%' GROUP BY vehicle_id"
                )
            ).all()
    finally:
        engine.dispose()
    return {row[0]: (int(row[1]), int(row[2])) for row in rows}


class ProcessWatch:
    """CPU time and resident memory of one process, from /proc (Linux)."""

    def __init__(self, pid: int) -> None:
        self.pid = pid
        self._ticks = os.sysconf("SC_CLK_TCK")
        self._last = (time.monotonic(), self._cpu_s())

    def cpu_seconds(self) -> float:
        return self._cpu_s()

    def _cpu_s(self) -> float:
        fields = Path(f"/proc/{self.pid}/stat").read_text().rsplit(")", 1)[1].split()
        return (int(fields[11]) + int(fields[12])) / self._ticks  # utime + stime

    def cpu_percent(self) -> float:
        """% of one core since the last call."""
        now, cpu = time.monotonic(), self._cpu_s()
        then, before = self._last
        self._last = (now, cpu)
        return 100.0 * (cpu - before) / max(1e-9, now - then)

    def rss(self) -> int:
        for line in Path(f"/proc/{self.pid}/status").read_text().splitlines():
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) * 1024
        return 0


def stored_after_drain(
    database_url: str, agent_results: list[dict[str, Any]]
) -> dict[str, tuple[int, int]]:
    """The store's counts once the hub has written what it holds: an agent that gave up
    waiting for its acks left frames in the hub's queue, which are stored, not lost."""
    sent = sum(sum(part["sent"].values()) for part in agent_results)
    counts = stored_counts(database_url)
    last_progress, stored = time.monotonic(), sum(c[1] for c in counts.values())
    while stored < sent and time.monotonic() - last_progress < 10:
        time.sleep(1)  # polling: the store announces nothing
        counts = stored_counts(database_url)
        if (now_stored := sum(c[1] for c in counts.values())) > stored:
            last_progress, stored = time.monotonic(), now_stored
    return counts


def percentile(values: list[float], fraction: float) -> float:
    if not values:
        return math.nan
    ordered = sorted(values)
    return ordered[min(len(ordered) - 1, int(fraction * len(ordered)))]


# -- the run -----------------------------------------------------------------------------


def enrol(urls: list[str], password: str, vehicles: int) -> dict[int, str]:
    """Tokens for an existing hub, through its admin API."""
    admin = admin_token(urls[0], password)
    tokens = {}
    with httpx.Client(
        base_url=urls[0], headers={"Authorization": f"Bearer {admin}"}, timeout=30
    ) as api:
        for index in range(vehicles):
            response = api.post(f"/api/v1/vehicles/{vehicle_id(index)}/agent-tokens")
            response.raise_for_status()
            tokens[index] = response.json()["token"]
    return tokens


def admin_token(url: str, password: str) -> str:
    response = httpx.post(
        f"{url}/api/v1/auth/token", data={"username": "admin", "password": password}, timeout=30
    )
    response.raise_for_status()
    token: str = response.json()["access_token"]
    return token


def run(args: argparse.Namespace) -> dict[str, Any]:
    context = multiprocessing.get_context("spawn")
    vehicles, rate = args.vehicles, args.rate
    processes = args.processes or max(1, min(4, math.ceil(vehicles / 250)))
    log_path = Path(tempfile.gettempdir()) / f"bench-scale-hub-{os.getpid()}.log"
    with contextlib.ExitStack() as stack:
        data_url: str | None = args.database
        hub_pid = args.hub_pid
        if args.hub_url:
            urls = list(args.hub_url)
            tokens = enrol(urls, args.admin_password, vehicles)
            password = args.admin_password
        else:
            tokens = {i: f"bench-{secrets.token_urlsafe(24)}" for i in range(vehicles)}
            url, hub_pid = stack.enter_context(
                started_hub(vehicles, args.database, tokens, log_path)
            )
            urls = [url]
            password = ADMIN_PASSWORD
            if data_url is None:
                data_url = f"sqlite:///{hub_data_dir(hub_pid) / 'gcs.sqlite3'}"
        token = admin_token(urls[0], password)

        connected = context.Queue()
        results = context.Queue()
        go = context.Event()
        stop_dashboards = context.Event()
        start_box = context.Value("d", 0.0)
        dashboards = context.Process(
            target=dashboard_process,
            args=(urls, token, args.dashboards, connected, stop_dashboards, results),
        )
        dashboards.start()
        if args.dashboards:
            connected.get(timeout=60)
        groups = [list(range(vehicles))[p::processes] for p in range(processes)]
        workers = [
            context.Process(
                target=agent_process,
                args=(
                    urls,
                    group,
                    {i: tokens[i] for i in group},
                    rate,
                    args.duration,
                    None if args.agent_compression == "none" else "deflate",
                    connected,
                    go,
                    start_box,
                    results,
                ),
            )
            for group in groups
        ]
        for worker in workers:
            worker.start()
        for _ in workers:
            connected.get(timeout=120)
        hub = ProcessWatch(hub_pid) if hub_pid else None
        start_box.value = time.time() + 1.0
        go.set()
        samples_cpu: list[float] = []
        peak_rss = 0
        run_end = start_box.value + args.duration
        cpu_at_start = hub.cpu_seconds() if hub is not None else 0.0
        while time.time() < run_end:
            time.sleep(1.0)
            if hub is not None:
                busy = hub.cpu_percent()
                if time.time() > start_box.value + 1:
                    samples_cpu.append(busy)
                peak_rss = max(peak_rss, hub.rss())
        agent_results = []
        for _ in workers:
            agent_results.append(results.get(timeout=DRAIN_TIMEOUT_S + 120))
        # Everything sent is stored and acked by now: the hub's work for the run is done.
        cpu_used = hub.cpu_seconds() - cpu_at_start if hub is not None else None
        for worker in workers:
            worker.join(30)
        stop_dashboards.set()
        dashboard_results = results.get(timeout=60)
        dashboards.join(30)
        if hub is not None:
            peak_rss = max(peak_rss, hub.rss())
        counts = stored_after_drain(data_url, agent_results) if data_url else {}

    sent: dict[str, int] = {}
    acked: dict[str, int] = {}
    ack_delays: list[float] = []
    refused: list[str] = []
    last_ack_at = 0.0
    late = 0
    for part in agent_results:
        sent.update(part["sent"])
        acked.update(part["acked"])
        ack_delays += part["ack_delays_ms"]
        refused += part["refused"]
        last_ack_at = max(last_ack_at, part["last_ack_at"])
        late += part["late_slots"]
    total_sent = sum(sent.values())
    stored_rows = sum(c[0] for c in counts.values())
    distinct = sum(c[1] for c in counts.values())
    db_missing = sum(max(0, n - counts.get(v, (0, 0))[1]) for v, n in sent.items())
    delays: list[float] = []
    regressions = repeats = final_missing = updates = frames = bytes_in = 0
    closed: list[str] = []
    for dash in dashboard_results:
        delays += dash["delays_ms"]
        regressions += dash["regressions"]
        repeats += dash["repeats"]
        updates += dash["updates"]
        frames += dash["frames"]
        bytes_in += dash["bytes_in"]
        closed += dash["closed"]
        final_missing += sum(
            1 for v, n in sent.items() if n and dash["last_seq"].get(v, -1) != n - 1
        )
    start = start_box.value
    store_span = max(1e-9, (last_ack_at or run_end) - start)
    figures = {
        "vehicles": vehicles,
        "rate_hz": rate,
        "dashboards": args.dashboards,
        "duration_s": args.duration,
        "database": "postgresql" if (args.database or "").startswith("postgres") else "sqlite",
        "hubs": len(urls),
        "agent_processes": processes,
        "agent_compression": args.agent_compression,
        "frames_sent": total_sent,
        "sent_per_s": round(total_sent / args.duration, 1),
        "late_send_slots": late,
        "rows_stored": stored_rows,
        "stored_per_s": round(distinct / store_span, 1),
        "db_lost": db_missing,
        "db_duplicates": stored_rows - distinct,
        "unacked_vehicles": sum(1 for v, n in sent.items() if n and acked.get(v, -1) != n - 1),
        "ack_p50_ms": round(percentile(ack_delays, 0.5), 1),
        "ack_p99_ms": round(percentile(ack_delays, 0.99), 1),
        "dash_frames_per_s": round(frames / max(1, args.dashboards) / args.duration, 1),
        "dash_updates": updates,
        "dash_kib_per_s": round(bytes_in / 1024 / max(1, args.dashboards) / args.duration, 1),
        "dash_regressions": regressions,
        "dash_duplicates": repeats,
        "dash_final_missing": final_missing,
        "dash_closed": closed,
        "delay_p50_ms": round(percentile(delays, 0.5), 1),
        "delay_p95_ms": round(percentile(delays, 0.95), 1),
        "delay_p99_ms": round(percentile(delays, 0.99), 1),
        "delay_max_ms": round(max(delays, default=math.nan), 1),
        "hub_cpu_mean_pct": round(statistics.fmean(samples_cpu), 1) if samples_cpu else None,
        "hub_cpu_max_pct": round(max(samples_cpu), 1) if samples_cpu else None,
        # The hub's CPU time per frame sent (ingest, storage, fan-out to every dashboard),
        # from the start of sending until the last ack: what a busy machine cannot hide.
        "hub_cpu_us_per_frame": round(cpu_used / total_sent * 1e6, 1)
        if cpu_used is not None and total_sent
        else None,
        "hub_rss_peak_mib": round(peak_rss / 2**20, 1) if peak_rss else None,
        "load_average_1m": round(os.getloadavg()[0], 2),
        "refused": refused[:10],
    }
    return figures


def table(figures: dict[str, Any]) -> str:
    rows = [
        ("vehicles x rate", f"{figures['vehicles']} x {figures['rate_hz']:g} Hz"),
        (
            "dashboards / hubs / db",
            f"{figures['dashboards']} / {figures['hubs']} / {figures['database']}",
        ),
        ("sent / stored per s", f"{figures['sent_per_s']:g} / {figures['stored_per_s']:g}"),
        ("db lost / duplicates", f"{figures['db_lost']} / {figures['db_duplicates']}"),
        (
            "dash regressions / dup / final missing",
            f"{figures['dash_regressions']} / {figures['dash_duplicates']} / "
            f"{figures['dash_final_missing']}",
        ),
        (
            "agent->dashboard p50 / p95 / p99 ms",
            f"{figures['delay_p50_ms']} / {figures['delay_p95_ms']} / {figures['delay_p99_ms']}",
        ),
        ("agent->ack p50 / p99 ms", f"{figures['ack_p50_ms']} / {figures['ack_p99_ms']}"),
        (
            "dashboard frames/s, KiB/s",
            f"{figures['dash_frames_per_s']}, {figures['dash_kib_per_s']}",
        ),
        (
            "hub CPU mean / max %, RSS MiB",
            f"{figures['hub_cpu_mean_pct']} / "
            f"{figures['hub_cpu_max_pct']}, {figures['hub_rss_peak_mib']}",
        ),
        (
            "late send slots, load avg",
            f"{figures['late_send_slots']}, {figures['load_average_1m']}",
        ),
    ]
    width = max(len(name) for name, _ in rows)
    return "\n".join(f"{name:<{width}}  {value}" for name, value in rows)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--vehicles", type=int, default=100)
    parser.add_argument("--rate", type=float, default=10.0, help="telemetry Hz per vehicle")
    parser.add_argument("--dashboards", type=int, default=5)
    parser.add_argument("--duration", type=float, default=20.0, help="seconds of sending")
    parser.add_argument(
        "--database", help="a SQLAlchemy URL for the hub started here (default: its SQLite)"
    )
    parser.add_argument(
        "--hub-url", action="append", help="an existing hub (repeatable); none: start one"
    )
    parser.add_argument("--hub-pid", type=int, help="the existing hub's process, for CPU/RSS")
    parser.add_argument("--admin-password", default=os.environ.get("GCS_ADMIN_PASSWORD", ""))
    parser.add_argument("--processes", type=int, help="agent processes (default: 1 per 250)")
    parser.add_argument("--agent-compression", choices=["deflate", "none"], default="none")
    parser.add_argument("--json", type=Path, help="write the figures here")
    args = parser.parse_args(argv)
    figures = run(args)
    print(table(figures))
    if figures["refused"] or figures["dash_closed"]:
        print("refused:", figures["refused"], "dashboards closed:", figures["dash_closed"])
    if args.json:
        args.json.write_text(json.dumps(figures, indent=2) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
