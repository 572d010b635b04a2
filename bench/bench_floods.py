"""The hub under floods: `/health` round trips while one kind of abuse runs for a while.

    .venv/bin/python bench/bench_floods.py                  # every flood, 20 s each
    options: --seconds 20 --vehicles 3 --only logins,dashboards

A hub with a simulated fleet runs as real processes on loopback (`gcs.launcher`), as in
the demo. For each flood in turn, a prober process asks `/health` every 50 ms and the
flood runs from this process for `--seconds`; then the prober's round trips print as p50,
p99 and max (the bar in DESIGN.md: p99 <= 100 ms under every flood), with what the flood
got back (status codes). Loopback only; every loop is bounded in time and count.

- idle: no flood, the reference;
- logins: 32 clients with wrong passwords, each from its own loopback address
  (127.0.0.2-33), so the per-address limit alone does not stop them;
- dashboards: 200 live feeds that never read (4 KB receive buffers), then vanish;
- photos: one agent token, 16 clients each starting photo uploads of a declared 40 MB and
  sending 256 KiB chunks, never finishing one;
- previews: 8 operators' clients post survey previews in turn: a 4.4 km square at 1 m and
  a 200 m one at 1 m (both refused from their estimates) and a 200 m one at 5 m (planned);
- imports: 20 operators each post area files: KML of 45,000 vertices (refused once
  counted) and of 9,000 (parsed), until each user's imports a minute are spent (429);
Prints figures; asserts nothing.
"""

from __future__ import annotations

import argparse
import asyncio
import base64
import os
import socket
import statistics
import struct
import subprocess
import sys
import tempfile
import time
import uuid
from collections import Counter
from collections.abc import Callable, Coroutine
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import httpx

from common.geodesy import LocalFrame
from gcs.launcher import FleetPlan, LocalFleet, free_port
from protocol.photos import MAX_PHOTO_BYTES, PhotoMeta
from tests.integration.imagery.test_photo_routes import CAMERA, POSE
from tests.integration.test_hub_bad_input import scripted_agent
from tests.support.api import access_token
from tests.support.survey_shapes import kml_polygon

PROBE_EVERY_S = 0.05
PASSWORD = "correct horse battery"
MAX_REQUESTS = 200_000  # a bound on any flood's loop, whatever its duration

PROBE = """
import sys, time, httpx
base, seconds, every = sys.argv[1], float(sys.argv[2]), float(sys.argv[3])
end = time.monotonic() + seconds
with httpx.Client(base_url=base, timeout=10) as client:
    while time.monotonic() < end:
        started = time.perf_counter()
        try:
            client.get("/health")
            print(f"{(time.perf_counter() - started) * 1e3:.2f}", flush=True)
        except httpx.HTTPError:
            print("timeout", flush=True)
        time.sleep(every)
"""


@dataclass
class Flood:
    base: str
    admin_token: str
    seconds: float
    statuses: Counter[str] = field(default_factory=Counter)
    prober: subprocess.Popen[str] | None = None

    def until(self) -> float:
        """Starts the /health prober (a flood's set-up, before this, is not measured);
        when the flood ends."""
        self.prober = subprocess.Popen(
            [sys.executable, "-c", PROBE, self.base, str(self.seconds), str(PROBE_EVERY_S)],
            stdout=subprocess.PIPE,
            text=True,
        )
        return time.monotonic() + self.seconds


async def logins(flood: Flood) -> None:
    end = flood.until()
    requests = 0

    async def client(index: int) -> None:
        nonlocal requests
        transport = httpx.AsyncHTTPTransport(local_address=f"127.0.0.{2 + index}")
        async with httpx.AsyncClient(base_url=flood.base, transport=transport, timeout=30) as http:
            while time.monotonic() < end and requests < MAX_REQUESTS:
                requests += 1
                got = await http.post(
                    "/api/v1/auth/token",
                    data={"username": f"guess{requests}", "password": "not-the-password"},
                )
                flood.statuses[str(got.status_code)] += 1

    async with asyncio.TaskGroup() as tasks:
        for index in range(32):
            tasks.create_task(client(index))


def _feed_socket(address: tuple[str, int], token: str) -> socket.socket:
    """A dashboard's live feed, opened by hand and then never read."""
    sock = socket.socket()
    sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4096)
    sock.connect(address)
    key = base64.b64encode(os.urandom(16)).decode()
    sock.sendall(
        (
            f"GET /api/v1/ws HTTP/1.1\r\nHost: {address[0]}\r\nUpgrade: websocket\r\n"
            f"Connection: Upgrade\r\nSec-WebSocket-Key: {key}\r\n"
            f"Sec-WebSocket-Version: 13\r\nAuthorization: Bearer {token}\r\n\r\n"
        ).encode()
    )
    return sock


async def dashboards(flood: Flood) -> None:
    host, port = flood.base.removeprefix("http://").split(":")
    sockets = [_feed_socket((host, int(port)), flood.admin_token) for _ in range(200)]
    flood.statuses["opened"] += len(sockets)
    await asyncio.sleep(flood.until() - time.monotonic())  # the flood is their not reading
    for sock in sockets:  # gone without a close frame: a reset
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_LINGER, struct.pack("ii", 1, 0))
        sock.close()


async def idle(flood: Flood) -> None:
    """No flood: the figures to read the others against."""
    await asyncio.sleep(flood.until() - time.monotonic())


def _enrolled(base: str, admin_token: str, vehicle: str) -> str:
    """An agent token for ``vehicle``, which the hub then knows (it connected once)."""
    created = httpx.post(
        f"{base}/api/v1/vehicles/{vehicle}/agent-tokens",
        headers={"Authorization": f"Bearer {admin_token}"},
    )
    created.raise_for_status()
    token: str = created.json()["token"]
    with scripted_agent(base, vehicle, token):
        pass
    return token


async def photos(flood: Flood) -> None:
    vehicle = "flood_1"
    token = await asyncio.to_thread(_enrolled, flood.base, flood.admin_token, vehicle)
    chunk = os.urandom(256 * 1024)
    end = flood.until()
    started = 0
    refusals: list[str] = []

    async def client(http: httpx.AsyncClient) -> None:
        nonlocal started
        while time.monotonic() < end and started < MAX_REQUESTS:
            started += 1
            photo_id = f"{vehicle}-1-{started:05d}"
            meta = PhotoMeta(
                photo_id=photo_id,
                index=started,
                size_bytes=MAX_PHOTO_BYTES,
                pose=POSE,
                camera=CAMERA,
            )
            offset = 0
            headers = {"X-Photo-Meta": meta.model_dump_json()}
            while time.monotonic() < end:
                got = await http.put(
                    f"/api/v1/vehicles/{vehicle}/photos/{photo_id}",
                    params={"offset": offset},
                    content=chunk,
                    headers=headers if offset == 0 else {},
                )
                flood.statuses[str(got.status_code)] += 1
                if got.status_code == 422 and not refusals:
                    refusals.append(got.text)  # printed once: what the hub said
                if got.status_code != 200:
                    break  # refused: start another photo
                offset += len(chunk)

    auth = {"Authorization": f"Bearer {token}"}
    async with (
        httpx.AsyncClient(base_url=flood.base, headers=auth, timeout=30) as http,
        asyncio.TaskGroup() as tasks,
    ):
        for _ in range(16):
            tasks.create_task(client(http))
    for text in refusals:
        print(f"photos: a 422 said {text[:300]}")


def _square(vehicle: dict[str, Any], side_m: float, altitude_m: float) -> dict[str, Any]:
    frame = LocalFrame(vehicle["lat"], vehicle["lon"], 0.0)
    corners = [(50, 50), (50 + side_m, 50), (50 + side_m, 50 + side_m), (50, 50 + side_m)]
    ring = [[lon, lat] for lat, lon in (frame.to_geo(x, y) for x, y in corners)]
    return {
        "area": {"type": "Polygon", "coordinates": [[*ring, ring[0]]]},
        "camera": "sony_a6000_16mm",
        "altitude_m": altitude_m,
        "vehicle_ids": [vehicle["id"]],
    }


def _operators(base: str, admin_token: str, count: int) -> list[str]:
    """``count`` new operators' tokens (the imports' rate is per user)."""
    tokens = []
    with httpx.Client(base_url=base, headers={"Authorization": f"Bearer {admin_token}"}) as admin:
        for _ in range(count):
            name = f"flood-{uuid.uuid4().hex[:8]}"
            admin.post(
                "/api/v1/users", json={"username": name, "password": PASSWORD, "role": "operator"}
            ).raise_for_status()
            tokens.append(access_token(base, name, PASSWORD))
    return tokens


async def _posting(flood: Flood, tokens: list[str], path: str, bodies: list[Any]) -> None:
    """Each token's client posts ``bodies`` in turn to ``path`` until the flood ends."""
    end = flood.until()
    sent = 0

    async def client(token: str) -> None:
        nonlocal sent
        auth = {"Authorization": f"Bearer {token}"}
        async with httpx.AsyncClient(base_url=flood.base, headers=auth, timeout=120) as http:
            while time.monotonic() < end and sent < MAX_REQUESTS:
                sent += 1
                got = await http.post(path, json=bodies[sent % len(bodies)])
                flood.statuses[str(got.status_code)] += 1

    async with asyncio.TaskGroup() as tasks:
        for token in tokens:
            tasks.create_task(client(token))


async def previews(flood: Flood) -> None:
    auth = {"Authorization": f"Bearer {flood.admin_token}"}
    async with httpx.AsyncClient(base_url=flood.base, headers=auth) as http:
        fleet = (await http.get("/api/v1/vehicles")).json()
    vehicle = next(v for v in fleet if v["id"].startswith("sim_") and v["state"])
    here = {"id": vehicle["id"], **vehicle["state"]}
    bodies = [_square(here, 4400, 1), _square(here, 200, 1), _square(here, 200, 5)]
    tokens = await asyncio.to_thread(_operators, flood.base, flood.admin_token, 8)
    await _posting(flood, tokens, "/api/v1/surveys/preview", bodies)


async def imports(flood: Flood) -> None:
    files = [
        {"format": "kml", "content": kml_polygon(45_000)},
        {"format": "kml", "content": kml_polygon(9_000)},
    ]
    tokens = await asyncio.to_thread(_operators, flood.base, flood.admin_token, 20)
    await _posting(flood, tokens, "/api/v1/surveys/import", files)


FLOODS: dict[str, Callable[[Flood], Coroutine[Any, Any, None]]] = {
    "idle": idle,
    "logins": logins,
    "dashboards": dashboards,
    "photos": photos,
    "previews": previews,
    "imports": imports,
}


def percentile(values: list[float], share: float) -> float:
    ordered = sorted(values)
    return ordered[min(len(ordered) - 1, int(len(ordered) * share))]


def run_flood(name: str, base: str, token: str, seconds: float) -> None:
    flood = Flood(base, token, seconds)
    started = time.monotonic()
    asyncio.run(FLOODS[name](flood))
    assert flood.prober is not None, f"{name} never started its clock"
    output, _ = flood.prober.communicate(timeout=seconds + 60)
    lines = output.split()
    times = [float(line) for line in lines if line != "timeout"]
    lost = len(lines) - len(times)
    answers = ", ".join(f"{code}: {count}" for code, count in sorted(flood.statuses.items()))
    if not times:
        print(f"{name:<11} no /health answer in {time.monotonic() - started:.0f} s")
        return
    print(
        f"{name:<11} /health p50 {statistics.median(times):6.1f} ms  "
        f"p99 {percentile(times, 0.99):6.1f} ms  max {max(times):7.1f} ms  "
        f"({len(times)} probes, {lost} timed out)  flood answers: {answers}"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--seconds", type=float, default=20.0)
    parser.add_argument("--vehicles", type=int, default=3)
    parser.add_argument("--only", default=",".join(FLOODS))
    args = parser.parse_args()
    names = [name for name in args.only.split(",") if name]
    with tempfile.TemporaryDirectory() as folder:
        plan = FleetPlan(port=free_port(), data_dir=Path(folder), vehicles=args.vehicles)
        with LocalFleet(plan) as fleet:
            fleet.start()
            fleet.wait_until_ready()
            base = plan.hub_http
            token = access_token(base, "admin", plan.admin_password)
            print(f"hub with {args.vehicles} simulated vehicles; {args.seconds:g} s per flood")
            for name in names:
                run_flood(name, base, token, args.seconds)


if __name__ == "__main__":
    main()
