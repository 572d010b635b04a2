"""Survey planning and area imports under a flood: does the hub keep answering?

    .venv/bin/python bench/bench_survey_bounds.py     # about a minute on 2 cores
    options: --seconds 15 (each flood), --clients 8, --max-requests 400

A real hub with two simulated drones and their agents (processes on loopback), then:

- idle: /health round trips with nothing else going on;
- previews: `--clients` threads post survey previews for `--seconds` (at most
  `--max-requests` in all): a 4.4 km square at 1 m (refused from its estimate), a 200 m
  square at 1 m (the same), and a 200 m square at 5 m (within the limits: seconds of
  planning for the two drones), in turn;
- imports: 20 users each post area files for `--seconds`: a KML of 45,000 vertices
  (refused once counted, 422) and one of 9,000 (parsed, 200), in turn, until each user's
  `GCS_SURVEY_IMPORTS_PER_MINUTE` is spent (429).

During each, a thread of its own asks /health every 50 ms; its round trips' p50, p99 and
worst are printed with the answers' status counts. Loopback only; prints figures, asserts
nothing.
"""

from __future__ import annotations

import argparse
import collections
import statistics
import sys
import tempfile
import threading
import time
import uuid
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import Any

import httpx

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from common.geodesy import LocalFrame
from tests.helpers import FleetWatcher, access_token, api_client, ready, running_fleet

VEHICLES = ["sim_1", "sim_2"]
PASSWORD = "correct horse battery"


def _square(state: dict[str, Any], side_m: float, altitude_m: float) -> dict[str, Any]:
    frame = LocalFrame(state["lat"], state["lon"], 0.0)
    corners = [(50, 50), (50 + side_m, 50), (50 + side_m, 50 + side_m), (50, 50 + side_m)]
    ring = [[lon, lat] for lat, lon in (frame.to_geo(x, y) for x, y in corners)]
    return {
        "area": {"type": "Polygon", "coordinates": [[*ring, ring[0]]]},
        "camera": "sony_a6000_16mm",
        "altitude_m": altitude_m,
        "vehicle_ids": VEHICLES,
    }


def _kml(vertices: int) -> str:
    points = " ".join(f"{8 + k * 1e-6:.6f},47.000000" for k in range(vertices - 1))
    return (
        '<kml xmlns="http://www.opengis.net/kml/2.2"><Placemark><Polygon><outerBoundaryIs>'
        f"<LinearRing><coordinates>{points} 8.5,47.5</coordinates></LinearRing>"
        "</outerBoundaryIs></Polygon></Placemark></kml>"
    )


class HealthProbe:
    def __init__(self, base_url: str) -> None:
        self._url = f"{base_url}/api/v1/health"
        self._stop = threading.Event()
        self.round_trips_ms: list[float] = []
        self._thread = threading.Thread(target=self._run, daemon=True)

    def _run(self) -> None:
        with httpx.Client(timeout=60) as client:
            while not self._stop.is_set():
                started = time.perf_counter()
                client.get(self._url)
                self.round_trips_ms.append((time.perf_counter() - started) * 1000)
                self._stop.wait(0.05)

    def __enter__(self) -> HealthProbe:
        self._thread.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self._stop.set()
        self._thread.join(60)


def _flood(
    base_url: str,
    clients: int,
    seconds: float,
    max_requests: int,
    send: Callable[[int, int], int],
) -> tuple[collections.Counter[int], list[float]]:
    """`clients` threads call send(client, n) until `seconds` pass or `max_requests` are
    sent; the status counts and /health round trips meanwhile."""
    statuses: collections.Counter[int] = collections.Counter()
    sent = iter(range(max_requests))
    lock = threading.Lock()
    deadline = time.monotonic() + seconds

    def client(index: int) -> None:
        while time.monotonic() < deadline:
            with lock:
                n = next(sent, None)
            if n is None:
                return
            status = send(index, n)
            with lock:
                statuses[status] += 1

    with HealthProbe(base_url) as probe, ThreadPoolExecutor(clients) as pool:
        list(pool.map(client, range(clients)))
    return statuses, probe.round_trips_ms


def _row(name: str, statuses: collections.Counter[int], trips: list[float]) -> str:
    ordered = sorted(trips)
    p99 = ordered[min(len(ordered) - 1, int(0.99 * len(ordered)))]
    answers = ", ".join(f"{code}: {count}" for code, count in sorted(statuses.items())) or "-"
    return (
        f"| {name} | {answers} | {len(trips)} | {statistics.median(trips):.1f} | "
        f"{p99:.1f} | {max(trips):.1f} |"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--seconds", type=float, default=15.0)
    parser.add_argument("--clients", type=int, default=8)
    parser.add_argument("--max-requests", type=int, default=400)
    args = parser.parse_args()
    with (
        tempfile.TemporaryDirectory() as scratch,
        running_fleet(Path(scratch), vehicles=len(VEHICLES)) as fleet,
    ):
        base = fleet.plan.hub_http
        token = access_token(base, "admin", fleet.plan.admin_password)
        with FleetWatcher(base, token) as watcher:
            for vehicle in VEHICLES:
                watcher.wait_until(ready(vehicle), 120, f"{vehicle} ready")
            state = watcher.state("sim_1")
        rows = ["| flood | answers (status: count) | /health probes | p50 ms | p99 ms | max ms |"]
        rows.append("| --- | --- | --- | --- | --- | --- |")

        with HealthProbe(base) as probe:
            time.sleep(min(5.0, args.seconds))
        rows.append(_row("idle", collections.Counter(), probe.round_trips_ms))

        bodies = [_square(state, 4400, 1), _square(state, 200, 1), _square(state, 200, 5)]
        with api_client(base, token, timeout_s=120) as api:

            def preview(_client: int, n: int) -> int:
                answer = api.post("/api/v1/surveys/preview", json=bodies[n % len(bodies)])
                return answer.status_code

            statuses, trips = _flood(base, args.clients, args.seconds, args.max_requests, preview)
        rows.append(_row("survey previews", statuses, trips))

        users = []
        with api_client(base, token) as admin:
            for _ in range(20):
                name = f"operator-{uuid.uuid4().hex[:6]}"
                created = admin.post(
                    "/api/v1/users",
                    json={"username": name, "password": PASSWORD, "role": "operator"},
                )
                created.raise_for_status()
                users.append(api_client(base, access_token(base, name, PASSWORD), timeout_s=120))
        files = [
            {"format": "kml", "content": _kml(45_000)},
            {"format": "kml", "content": _kml(9_000)},
        ]

        def upload(client: int, n: int) -> int:
            return users[client].post("/api/v1/surveys/import", json=files[n % 2]).status_code

        statuses, trips = _flood(base, len(users), args.seconds, args.max_requests, upload)
        for user in users:
            user.close()
        rows.append(_row("area imports (20 users)", statuses, trips))
    print("\n".join(rows))


if __name__ == "__main__":
    main()
