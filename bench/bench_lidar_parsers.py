"""Each serial LIDAR parser's CPU per 1,000 points, on the simulator's bytes in that wire
format, and what that is for a 10 Hz, 720-point scan (7,200 points a second).

    .venv/bin/python bench/bench_lidar_parsers.py            # about a minute
    options: --seconds 20 (of sensor output per format), --repeat 3 (best of)

The bar (issue 35): <= 3 % of one core for a 10 Hz, 720-point scan, per parser. The
bytes are made beforehand and fed in 4,096-byte reads, as the agent's source reads a
serial port; "parse" is the parser alone, "+ turns" adds the agent's assembly of packets
into turns (the rest of the source's work per point). CPU is process time, so other load
on the machine does not count against it. Prints a table; asserts nothing.
"""

from __future__ import annotations

import argparse
import time

from gcs.demo_lidars import DEMO_LIDARS
from simulator.outputs.lidar import wire_format
from simulator.sensors.lidar import Lidar, LidarSpec, Pose
from simulator.world.obstacles import default_scene
from vehicle_agents.sensors.lidar.models import MODELS, make_parser
from vehicle_agents.sensors.turn_assembly import TurnAssembler

READ = 4096
POINTS_PER_S = 7200  # 720 points at 10 Hz
DESCRIPTORS = {
    "rplidar-express": b"\xa5\x5a\x54\x00\x00\x40\x82",
    "rplidar-dense": b"\xa5\x5a\x54\x00\x00\x40\x85",
    "rplidar-ultra": b"\xa5\x5a\x84\x00\x00\x40\x84",
}


def stream(name: str, seconds: float) -> bytes:
    demo = DEMO_LIDARS[name]
    wire = wire_format(demo.wire)
    capsules = demo.scan_mode != 0
    mode = next(m for m in wire.encoders if (m != "standard") == capsules or m == "scan")
    encoder = wire.encoders[mode](720)
    lidar = Lidar(default_scene(), LidarSpec(), seed=4)
    out = bytearray(DESCRIPTORS.get(demo.wire, b""))
    for i in range(round(seconds / 0.02) + 1):
        beams = lidar.advance(Pose(i * 0.02, 0.0, 0.0, 1.5, 0.0, 0.0, 0.01 * i))
        if beams is not None:
            out += encoder.encode(beams, 10.0)
    return bytes(out)


def measure(name: str, data: bytes, turns: bool) -> tuple[float, int]:
    """CPU seconds to parse ``data`` (and assemble turns), and the points decoded."""
    parser = make_parser(MODELS[DEMO_LIDARS[name].model])
    assembler = TurnAssembler()
    chunks = [data[i : i + READ] for i in range(0, len(data), READ)]
    start = time.process_time()
    for n, chunk in enumerate(chunks):
        packets = parser.feed(chunk)
        if turns:
            for packet in packets:
                assembler.add(packet, n * 0.01)
    return time.process_time() - start, parser.stats.points


def main() -> None:
    options = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    options.add_argument("--seconds", type=float, default=20.0)
    options.add_argument("--repeat", type=int, default=3)
    args = options.parse_args()
    print(
        f"{'format (model)':34} {'points':>8} {'parse us/1k':>12} {'+turns us/1k':>13} "
        f"{'% core @7.2k/s':>15}"
    )
    worst = 0.0
    for name in DEMO_LIDARS:
        data = stream(name, args.seconds)
        parse = min(measure(name, data, False)[0] for _ in range(args.repeat))
        both, points = min(
            (measure(name, data, True) for _ in range(args.repeat)), key=lambda r: r[0]
        )
        per_k_parse = parse / points * 1e6 * 1000
        per_k_both = both / points * 1e6 * 1000
        share = per_k_both * POINTS_PER_S / 1000 / 1e6 * 100
        worst = max(worst, share)
        label = f"{name} ({DEMO_LIDARS[name].model})"
        print(f"{label:34} {points:8d} {per_k_parse:12.0f} {per_k_both:13.0f} {share:14.2f}%")
    print(f"worst: {worst:.2f} % of one core for a 10 Hz, 720-point scan (bar: <= 3 %)")


if __name__ == "__main__":
    main()
