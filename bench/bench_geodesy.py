"""Geodesy benchmark: the cost of one call of each common/geodesy.py conversion, and of the
simulator's per-message position (GLOBAL_POSITION_INT, GPS_RAW_INT) built on it.

    .venv/bin/python bench/bench_geodesy.py [--calls 20000]

Prints microseconds per call; asserts nothing. The machine is shared and small, so each
figure is the best of several runs (the least disturbed one).
"""

from __future__ import annotations

import argparse
import sys
import timeit
from collections.abc import Callable
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from common.geodesy import LocalFrame, haversine_m
from simulator import DEFAULT_HOME, Copter


def _us_per_call(call: Callable[[], object], calls: int) -> float:
    return min(timeit.repeat(call, number=calls, repeat=5)) / calls * 1e6


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--calls", type=int, default=20_000)
    calls = parser.parse_args().calls

    frame = LocalFrame(DEFAULT_HOME.lat, DEFAULT_HOME.lon, DEFAULT_HOME.alt)
    lat, lon = frame.to_geo(300.0, -120.0)
    copter = Copter(DEFAULT_HOME)
    cases: list[tuple[str, Callable[[], object]]] = [
        ("LocalFrame.to_local", lambda: frame.to_local(lat, lon)),
        ("LocalFrame.to_geo", lambda: frame.to_geo(300.0, -120.0)),
        ("LocalFrame.to_enu", lambda: frame.to_enu(lat, lon, 600.0)),
        ("LocalFrame.from_enu", lambda: frame.from_enu(300.0, -120.0, 16.0)),
        ("haversine_m", lambda: haversine_m(DEFAULT_HOME.lat, DEFAULT_HOME.lon, lat, lon)),
        ("Copter.position (simulator)", copter.position),
        ("Copter.gps_position (simulator)", copter.gps_position),
    ]
    for name, call in cases:
        print(f"{name:34} {_us_per_call(call, calls):7.2f} µs/call")


if __name__ == "__main__":
    main()
