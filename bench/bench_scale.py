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
import contextlib
import json
import math
import multiprocessing
import os
import secrets
import statistics
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))


from bench.scale.agents import DRAIN_TIMEOUT_S, agent_process
from bench.scale.dashboards import dashboard_process
from bench.scale.figures import percentile, table
from bench.scale.hub_process import (
    ADMIN_PASSWORD,
    admin_token,
    enrol,
    hub_data_dir,
    started_hub,
    stored_after_drain,
)
from bench.scale.process_watch import ProcessWatch


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
