"""3D view benchmark: 50 vehicles moving at 10 Hz through the hub's scene mirror into
viser, and into viser's own client in headless Chromium, with and without LIDAR points.

    .venv/bin/python bench/bench_viz.py [--vehicles 50] [--rate-hz 10] [--seconds 10]

The hub's pieces run in this process, as the hub wires them: the realtime bus, the scan
service (its checks, its point map) and the scene mirror, which batches what changed into
one atomic viser update per period (GCS_VIZ_UPDATE_INTERVAL_S, 0.1 s). A load generator
publishes every vehicle's state at --rate-hz, each moving on its own circle, 40 m apart;
with LIDAR each vehicle also sends a full 720-beam turn at the same rate (every beam a
return at 6-10 m, the worst case for points: 7,200 a second a vehicle, 360,000 in all).

Measured over --seconds, after the scene has settled:
- scene messages: what viser sends one browser, counted by a second client on the same
  socket: WebSocket frames, viser messages inside them, and bytes, per second;
- the browser's frame time: the interval between animation frames in viser's client
  (requestAnimationFrame), p50, p95 and max, and the main thread's busy share.
Chromium opens viser's page on its loopback port directly: the hub's /viz/ relay passes
frames through unchanged, one hop, and is left out. Prints the figures; asserts nothing
(the machine is shared and small).
"""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import math
import statistics
import sys
import threading
import time
from array import array
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

import sqlalchemy
from websockets.asyncio.client import connect
from websockets.typing import Subprotocol

from backend.fleet.registry import FleetRegistry
from backend.realtime.bus import InProcessBus, Topic
from backend.scans.repository import ScanRepository
from backend.scans.scene_layer import scan_scene_layers
from backend.scans.service import ScanService
from backend.viz3d.frame import SceneFrame
from backend.viz3d.mirror import SceneMirror
from backend.viz3d.scene import FleetScene
from backend.viz3d.server import VizServer
from common.geodesy import GeoPoint, LocalFrame
from gcs.launcher import DEFAULT_HOME
from protocol.messages import VehicleState, VehicleSummary
from protocol.scans import ScanFrame, ScanPose, encode_scan
from tests.viz_wire import SUBPROTOCOL, scene_messages

CHROMIUM = "/usr/bin/chromium"
SPACING_M = 40.0
CIRCLE_M = 12.0
CIRCLE_S = 30.0
ALTITUDE_M = 20.0
BEAMS = 720
INTERVAL_S = 0.1

MEASURE_JS = """(seconds) => new Promise((resolve) => {
    const frames = [];
    let last = null;
    const end = performance.now() + seconds * 1000;
    function tick(now) {
        if (last !== null) frames.push(now - last);
        last = now;
        if (now < end) requestAnimationFrame(tick); else resolve(frames);
    }
    requestAnimationFrame(tick);
})"""


class Counter:
    """What one browser receives: frames, viser messages and bytes, while counting."""

    def __init__(self) -> None:
        self.counting = False
        self.frames = self.messages = self.bytes = 0

    async def run(self, url: str, headers: dict[str, str]) -> None:
        async with connect(
            url,
            additional_headers=headers,
            subprotocols=[Subprotocol(SUBPROTOCOL)],
            max_size=None,
            compression=None,
        ) as ws:
            async for frame in ws:
                if not self.counting or not isinstance(frame, bytes):
                    continue
                self.frames += 1
                self.bytes += len(frame)
                self.messages += len(scene_messages(frame))


def _position(site: LocalFrame, index: int, t: float) -> tuple[GeoPoint, float]:
    """Where vehicle ``index`` is at ``t`` on its circle, and its heading (degrees)."""
    columns = 8
    centre_e = (index % columns) * SPACING_M
    centre_n = (index // columns) * SPACING_M
    angle = 2 * math.pi * (t / CIRCLE_S) + index
    east = centre_e + CIRCLE_M * math.cos(angle)
    north = centre_n + CIRCLE_M * math.sin(angle)
    heading = math.degrees(math.pi - angle) % 360  # along the circle, anticlockwise
    return site.from_enu(east, north, ALTITUDE_M), heading


def _summary(site: LocalFrame, index: int, t: float) -> VehicleSummary:
    where, heading = _position(site, index, t)
    home = site.origin
    return VehicleSummary(
        id=f"bench_{index:02d}",
        autopilot="ardupilot",
        vehicle_type="quadrotor",
        modes=["GUIDED"],
        connected=True,
        last_seen=t,
        state=VehicleState(
            mode="GUIDED",
            armed=True,
            lat=where.lat,
            lon=where.lon,
            alt_msl=where.alt,
            alt_rel=ALTITUDE_M,
            heading_deg=heading,
            roll_deg=5.0,
            pitch_deg=-3.0,
            home_lat=home.lat,
            home_lon=home.lon,
            home_alt_msl=home.alt,
        ),
    )


def _scan(site: LocalFrame, index: int, t: float, seq: int, ranges: array[int]) -> bytes:
    where, heading = _position(site, index, t)
    pose = ScanPose(where.lat, where.lon, where.alt, yaw=math.radians(heading))
    frame = ScanFrame(
        seq=seq % 65536,
        sensor_time_us=0,
        utc_time=time.time(),
        duration_s=0.1,
        angle_min=0.0,
        angle_increment=-2 * math.pi / BEAMS,
        range_max_m=12.0,
        pose_start=pose,
        pose_end=pose,
        ranges=ranges,
    )
    return encode_scan(frame)


async def _load(
    bus: InProcessBus,
    scans: ScanService,
    site: LocalFrame,
    vehicles: int,
    rate_hz: float,
    lidar: bool,
    stop: asyncio.Event,
) -> None:
    # A room of uneven walls, 6 to 10 m away: every beam returns.
    ranges = array("H", [round(8000 + 2000 * math.sin(i * 0.05)) for i in range(BEAMS)])
    started = time.monotonic()
    tick = 0
    while not stop.is_set():
        t = time.monotonic() - started
        for index in range(vehicles):
            summary = _summary(site, index, t)
            await bus.publish(Topic.VEHICLE_STATE, summary.id, summary)
            if lidar:
                await scans.ingest(summary.id, "bench", _scan(site, index, t, tick, ranges))
            # Each vehicle is its own socket in the hub: let the others (the mirror) run.
            await asyncio.sleep(0)
        tick += 1
        if rate_hz == 0:  # a still fleet: drawn once, then nothing changes
            await stop.wait()
            return
        # Paced to the clock, not by sleeps of a fixed length: a slow tick is caught up.
        await asyncio.sleep(max(0.0, started + tick / rate_hz - time.monotonic()))


def _scans_in(scans: ScanService) -> int:
    return sum(counts.live for counts in scans.diagnostics.values())


def _percentile(values: list[float], fraction: float) -> float:
    ordered = sorted(values)
    return ordered[min(len(ordered) - 1, int(fraction * len(ordered)))]


def run_case(vehicles: int, rate_hz: float, seconds: float, lidar: bool) -> None:
    from playwright.sync_api import sync_playwright

    from tests.browser.conftest import CHROMIUM_ARGS

    viz = VizServer.start()
    site = LocalFrame(*DEFAULT_HOME)
    scene = FleetScene(viz.viser, SceneFrame(), trail_s=60.0)
    bus = InProcessBus()
    scans = ScanService(ScanRepository(sqlalchemy.create_engine("sqlite://")), bus, site=site)
    layers = scan_scene_layers(scans, bus)
    mirror = SceneMirror(scene, bus, FleetRegistry(), INTERVAL_S, layers=layers)
    counter = Counter()
    loop = asyncio.new_event_loop()
    stop = asyncio.Event()

    async def hub() -> None:
        async with asyncio.TaskGroup() as tasks:
            work = [
                tasks.create_task(mirror.run()),
                tasks.create_task(counter.run(viz.ws_url, viz.relay_headers)),
                tasks.create_task(_load(bus, scans, site, vehicles, rate_hz, lidar, stop)),
            ]
            await stop.wait()
            for task in work:
                task.cancel()

    thread = threading.Thread(
        target=lambda: loop.run_until_complete(_quietly(hub())), name="hub", daemon=True
    )
    thread.start()
    try:
        with sync_playwright() as playwright:
            browser = playwright.chromium.launch(
                executable_path=CHROMIUM, headless=True, args=CHROMIUM_ARGS
            )
            page = browser.new_page(viewport={"width": 1280, "height": 800})
            page.goto(viz.http_url + "/")
            page.locator("canvas").first.wait_for(timeout=60_000)
            deadline = time.monotonic() + 60
            while len(scene._vehicles) < vehicles and time.monotonic() < deadline:
                page.wait_for_timeout(200)
            page.wait_for_timeout(3000)  # the first scene and the trails' first seconds
            session = page.context.new_cdp_session(page)
            session.send("Performance.enable")

            def task_seconds() -> float:
                metrics = session.send("Performance.getMetrics")["metrics"]
                return float(next(m["value"] for m in metrics if m["name"] == "TaskDuration"))

            batches_before = scene.batches
            scans_before = _scans_in(scans)
            busy_before, wall_before = task_seconds(), time.monotonic()
            counter.counting = True
            frames = page.evaluate(MEASURE_JS, seconds)
            counter.counting = False
            wall = time.monotonic() - wall_before
            busy = (task_seconds() - busy_before) / wall
            batches = scene.batches - batches_before
            scans_in = _scans_in(scans) - scans_before
            page.screenshot(path=f"/tmp/bench_viz_{'lidar' if lidar else 'plain'}.png")
            browser.close()
    finally:
        loop.call_soon_threadsafe(stop.set)
        thread.join(30)
        viz.stop()
    points = (
        f"LIDAR {scans_in / wall:.0f} scans/s ingested of {vehicles * rate_hz:g} offered"
        if lidar
        else "no LIDAR"
    )
    print(
        f"{vehicles} vehicles at {rate_hz:g} Hz, {points}: "
        f"scene {counter.frames / wall:.1f} frames/s, {counter.messages / wall:.0f} messages/s, "
        f"{counter.bytes / wall / 1e6:.2f} MB/s to each browser ({batches / wall:.1f} vehicle "
        f"batches/s); browser {len(frames) / seconds:.1f} fps, frame time p50 "
        f"{statistics.median(frames):.1f} ms, p95 {_percentile(frames, 0.95):.1f} ms, "
        f"max {max(frames):.1f} ms; main thread busy {busy * 100:.0f} %",
        flush=True,
    )


async def _quietly(work: Any) -> None:
    with contextlib.suppress(asyncio.CancelledError, Exception):
        await work


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--vehicles", type=int, default=50)
    parser.add_argument("--rate-hz", type=float, default=10.0)
    parser.add_argument("--seconds", type=float, default=10.0)
    args = parser.parse_args()
    # First an empty scene, then the fleet standing still: what viser's client costs to
    # draw on this machine at all, and to draw the fleet without any update arriving.
    run_case(0, args.rate_hz, args.seconds, lidar=False)
    run_case(args.vehicles, 0.0, args.seconds, lidar=False)
    for lidar in (False, True):
        run_case(args.vehicles, args.rate_hz, args.seconds, lidar)
    return 0


if __name__ == "__main__":
    sys.exit(main())
