"""LIDAR scans: bytes on the wire, the agent's CPU for them, the hub's cost per scan, world
point error against the simulator's obstacles, and the point map's memory.

    .venv/bin/python bench/bench_scans.py            # all of it, about five minutes
    options: --seconds 20 (each agent measurement), --skip-agent, --map-scans 360000

Figures and their bars (docs/DESIGN.md, issue 18):
- bytes per 720-beam scan on the wire (the frame and the WebSocket header): <= 2 KB;
- the agent's CPU with a 10 Hz LIDAR relayed and 10 Hz telemetry, minus the same agent
  without the LIDAR (real processes: hub, simulator at real time, agent; CPU time from
  /proc over wall time; 100 % is one core): <= 3 % of one core added;
- world point error (distance to the nearest obstacle side or the ground) for scans from
  a moving, yawing drone, through the real parser, clock and frame (in process): median
  <= 5 cm;
- the hub's cost per scan (check, world points, point map; and the store, per scan in
  batches of 200 on SQLite);
- the point map's memory after ``--map-scans`` scans (360,000: an hour of 10 Hz scans
  from 10 drones circling the yard; a static site's map holds its surfaces, so it stops
  growing once they are seen, and GCS_SCAN_MAP_MAX_VOXELS bounds it in any case), and
  its memory at that bound (a fleet that keeps seeing new ground).
Prints a table; asserts nothing.
"""

from __future__ import annotations

import argparse
import math
import os
import tempfile
import time
import tracemalloc
from pathlib import Path

import numpy as np

from backend.realtime.bus import InProcessBus
from backend.scans.pointmap import PointMap
from backend.scans.points import world_points
from backend.scans.repository import ScanRepository, StoredScan
from backend.scans.service import ScanService
from backend.storage.database import make_engine, migrate
from common.geodesy import LocalFrame
from gcs.launcher import FleetPlan, LocalFleet, free_port
from protocol.scans import ScanFrame, ScanPose, decode_scan, encode_scan
from simulator.sensors.lidar import Lidar, Pose
from simulator.wire.ydlidar import encode_beams
from simulator.world.obstacles import default_scene
from vehicle_agents.sensors.lidar.ydlidar import YdlidarParser
from vehicle_agents.sensors.turn import Turn
from vehicle_agents.sensors.turn_assembly import TurnAssembler

SITE = LocalFrame(-35.363262, 149.165237, 584.0)
WORLD = default_scene()
WS_HEADER_BYTES = 8  # a client-to-server binary frame of 126..65535 bytes: 2 + 2 + mask 4


def _pose(t: float, phase: float = 0.0) -> Pose:
    """A drone circling the yard at 3 m/s, yawing as it goes, tilted into the turn."""
    radius, speed = 5.0, 3.0
    angle = phase + speed * t / radius
    return Pose(
        t,
        radius * math.cos(angle),
        radius * math.sin(angle),
        2.5,
        0.08,
        -0.05,
        (math.pi / 2 - angle - math.pi / 2) % (2 * math.pi),
    )


def _scan_pose(pose: Pose) -> ScanPose:
    lat, lon = SITE.to_geo(pose.east, pose.north)
    return ScanPose(lat, lon, SITE.origin.alt + pose.up, pose.roll, pose.pitch, pose.yaw)


def simulated_frames(count: int, phase: float = 0.0) -> list[bytes]:
    """Scans through the simulator's bytes, the agent's parser and turn clock, and the
    frame, with the poses where the simulator flew (the agent's interpolation aside)."""
    lidar, parser, assembler = Lidar(WORLD, seed=1), YdlidarParser(), TurnAssembler()
    frames: list[bytes] = []
    t = 0.0
    while len(frames) < count:
        beams = lidar.advance(_pose(t, phase))
        if beams is not None:
            for packet in parser.feed(encode_beams(beams, 10.0)):
                turn: Turn | None = assembler.add(packet, t)
                if turn is not None:
                    end = turn.start + turn.duration_s
                    frame = ScanFrame(
                        len(frames),
                        round(turn.start * 1e6),
                        time.time(),
                        turn.duration_s,
                        turn.angle_min,
                        turn.angle_increment,
                        turn.range_max_m,
                        _scan_pose(_pose(turn.start, phase)),
                        _scan_pose(_pose(end, phase)),
                        turn.ranges,
                    )
                    frames.append(encode_scan(frame))
        t += 0.02
    return frames


def point_error(frames: list[bytes]) -> tuple[float, float, int]:
    errors = []
    for data in frames:
        enu = world_points(decode_scan(data), SITE).enu
        errors.append(np.minimum(WORLD.distance_to_surface(enu), np.abs(enu[:, 2])))
    e = np.concatenate(errors)
    return float(np.median(e)), float(np.percentile(e, 99)), len(e)


def hub_cost(frames: list[bytes]) -> tuple[float, float]:
    """Microseconds per scan: checking + world points + point map; storing (SQLite)."""
    import asyncio

    service = ScanService(
        ScanRepository(make_engine("sqlite:///:memory:")),
        InProcessBus(),
        site=SITE,
        max_rate_hz=1e9,
        queue_limit=len(frames) + 1,
    )

    async def ingest_all() -> float:
        start = time.perf_counter()
        for data in frames:
            await service.ingest("v1", "s", data)
        return (time.perf_counter() - start) / len(frames) * 1e6

    per_scan = asyncio.run(ingest_all())
    with tempfile.TemporaryDirectory() as folder:
        engine = make_engine(f"sqlite:///{folder}/bench.sqlite3")
        migrate(engine)
        with engine.begin() as connection:
            connection.exec_driver_sql(
                "INSERT INTO vehicles VALUES ('v1', 'ardupilot', 'multirotor', 1, '', 0, 0)"
            )
        repository = ScanRepository(engine)
        rows = [StoredScan("v1", "s", i, time.time(), 720, data) for i, data in enumerate(frames)]
        start = time.perf_counter()
        for at in range(0, len(rows), 200):
            repository.insert(rows[at : at + 200])
        store = (time.perf_counter() - start) / len(rows) * 1e6
    return per_scan, store


def map_memory(scans: int, drones: int = 10) -> tuple[int, float, float]:
    """Voxels and traced bytes of a point map fed ``scans`` scans from ``drones`` drones
    circling at different phases; and the seconds it took."""
    per_drone = max(1, scans // drones)
    sources = [simulated_frames(min(per_drone, 600), phase=i) for i in range(drones)]
    tracemalloc.start()
    point_map = PointMap()
    points = [[world_points(decode_scan(d), SITE).enu for d in frames] for frames in sources]
    started = time.perf_counter()
    base = tracemalloc.get_traced_memory()[0]
    for i in range(per_drone):  # the fleet's scans, interleaved, cycling each drone's turns
        for drone in range(drones):
            batch = points[drone]
            point_map.add(batch[i % len(batch)], float(i))
    used = tracemalloc.get_traced_memory()[0] - base
    tracemalloc.stop()
    return len(point_map), used / 1e6, time.perf_counter() - started


def map_memory_at_bound(max_voxels: int = 500_000) -> tuple[int, float]:
    """The point map's worst case: a fleet that keeps seeing new ground fills it to its
    bound (GCS_SCAN_MAP_MAX_VOXELS), after which it evicts; traced bytes there."""
    rng = np.random.default_rng(1)
    tracemalloc.start()
    base = tracemalloc.get_traced_memory()[0]
    point_map = PointMap(max_voxels=max_voxels)
    for i in range(max_voxels // 700 + 100):  # scans of 700 points each on unseen ground
        point_map.add(rng.uniform(-2000.0, 2000.0, size=(700, 3)), float(i))
    used = tracemalloc.get_traced_memory()[0] - base
    tracemalloc.stop()
    return len(point_map), used / 1e6


def _cpu_seconds(pid: int) -> float:
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def agent_cpu(lidar: bool, seconds: float, warmup: float = 8.0) -> float:
    """Percent of one core the agent uses, with or without a 10 Hz LIDAR to relay."""
    with tempfile.TemporaryDirectory() as folder:
        plan = FleetPlan(vehicles=1, port=free_port(), data_dir=Path(folder), lidars=lidar)
        with LocalFleet(plan) as fleet:
            fleet.start()
            fleet.wait_until_ready()
            time.sleep(warmup)  # connected, streams requested, the LIDAR's clock settled
            agent = next(m.process for m in fleet.processes if m.name.startswith("agent"))
            cpu0, wall0 = _cpu_seconds(agent.pid), time.monotonic()
            time.sleep(seconds)
            cpu1, wall1 = _cpu_seconds(agent.pid), time.monotonic()
    return 100.0 * (cpu1 - cpu0) / (wall1 - wall0)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--seconds", type=float, default=20.0)
    parser.add_argument("--skip-agent", action="store_true")
    parser.add_argument("--map-scans", type=int, default=360_000)
    args = parser.parse_args()

    frames = simulated_frames(200)
    size = len(frames[0])
    median, p99, points = point_error(frames)
    ingest_us, store_us = hub_cost(frames)
    voxels, map_mb, map_s = map_memory(args.map_scans)
    bound_voxels, bound_mb = map_memory_at_bound()
    rows = [
        (
            "bytes per 720-beam scan (frame + WebSocket header)",
            f"{size} + {WS_HEADER_BYTES}",
            "<= 2048",
        ),
        (
            "world points: median / p99 error (moving 3 m/s, yawing)",
            f"{median * 100:.1f} cm / {p99 * 100:.1f} cm ({points} points)",
            "median <= 5 cm",
        ),
        ("hub: check + world points + point map, per scan", f"{ingest_us:.0f} us", ""),
        ("hub: store (SQLite, batches of 200), per scan", f"{store_us:.0f} us", ""),
        (
            f"point map after {args.map_scans} scans (10 drones)",
            f"{voxels} voxels, {map_mb:.1f} MB traced ({map_s:.0f} s)",
            "bounded: 500,000 voxels",
        ),
        (
            "point map at its bound (new ground all the time)",
            f"{bound_voxels} voxels, {bound_mb:.1f} MB traced",
            "",
        ),
    ]
    if not args.skip_agent:
        without = agent_cpu(False, args.seconds)
        with_lidar = agent_cpu(True, args.seconds)
        rows += [
            ("agent CPU, telemetry only", f"{without:.1f} % of a core", ""),
            ("agent CPU, telemetry + 10 Hz scans", f"{with_lidar:.1f} % of a core", ""),
            ("agent CPU added by scans", f"{with_lidar - without:.1f} % of a core", "<= 3 %"),
        ]
    width = max(len(r[0]) for r in rows)
    for name, value, bar in rows:
        print(f"{name:<{width}}  {value:<44} {bar}")


if __name__ == "__main__":
    main()
